"""The speed targets in one command: planner, service, CLI, scale and batch, each against its reference.

    python benchmarks/speed.py [--quick] [--base CHECKOUT] [--no-service]

Runs the benchmarks below one after another, each as its own process (so none is slowed by
another's imports or caches), shows their own output, and ends with one table: every target,
what was measured, the reference measured in the same run, and whether it is met. Every
target is a ratio; none is an absolute time.

- ``benchmarks/planners.py``: cold and repeated solves; reference: unified-planning's
  ``OneshotPlanner("fast-downward")`` on the same tasks (and, with ``--base``, the older code).
- ``benchmarks/service.py`` (unless ``--no-service``): POST /v1/plans on a real server.
- ``benchmarks/cli.py``: ``causalplan plan examples/paper/desk_lamp.yaml`` as a whole process;
  reference: a script doing the same solve through unified-planning.
- ``benchmarks/run.py --sizes 80,160,320``: synthetic assemblies; reference: the same tasks
  through unified-planning (axiom-free formulation, its Fast Downward engine).
- ``benchmarks/batch.py``: 1,000 simulated participants' trials through ``causalplan batch``;
  reference: the plain path, and with ``--base`` the older code's ``causalplan batch``.

``--base`` names a checkout of the code to compare with, e.g. after
``git worktree add /tmp/base 96c4986``. The exit code is 0 when every target is met, 1
otherwise. Results: benchmarks/results/*.json.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
SCALE_TARGETS = {80: 0.5, 160: 1.2, 320: 3.0}


@dataclass(frozen=True)
class Target:
    """One line of the summary."""

    what: str
    measured: str
    target: str
    reference: str
    met: bool


def run(script: str, *arguments: str) -> None:
    """Run one benchmark script with this Python, showing its output; stop if it crashes."""
    command = [sys.executable, str(ROOT / "benchmarks" / script), *arguments]
    print(f"\n$ python benchmarks/{script} {' '.join(arguments)}".rstrip(), flush=True)
    started = time.perf_counter()
    completed = subprocess.run(command, cwd=ROOT, check=False)
    # run.py exits 1 when its own (older, looser) target is missed; only a crash stops us.
    if completed.returncode not in (0, 1):
        sys.exit(f"benchmarks/{script} failed with exit code {completed.returncode}")
    print(f"({time.perf_counter() - started:.0f} s)", flush=True)


def load(name: str) -> Any:
    return json.loads((RESULTS / name).read_text(encoding="utf-8"))


def ms(seconds: float) -> str:
    return f"{seconds * 1000:.1f} ms"


def planner_targets(report: dict[str, Any]) -> list[Target]:
    """Cold vs UP, repeated vs cold, and what the prestarted search buys (kept only if >= 20%)."""
    p50 = report["p50_s"]
    cold = p50["ours, fresh process, prestart on"]
    up = p50["unified-planning"]
    targets = [
        Target(
            "cold solve vs UP OneshotPlanner, p50",
            f"{report['up_over_cold']:.1f}x faster ({ms(cold)})",
            ">= 10x",
            f"UP p50 {ms(up)}",
            bool(report["cold_met"]),
        ),
        Target(
            "repeated solve / cold, p50",
            f"{report['repeated_over_cold']:.3f} ({ms(p50['repeated'])})",
            "<= 0.3",
            f"cold p50 {ms(cold)}",
            bool(report["repeated_met"]),
        ),
    ]
    for name, share in report["prestart_share_of_cold"].items():
        if name != "ours":  # the older code's share is printed by planners.py, for comparison
            continue
        off = p50[f"{name}, fresh process, prestart off"]
        targets.append(
            Target(
                f"{name}: share of cold path a prestart buys", f"{share:.0%}", ">= 20%", f"off {ms(off)}", share >= 0.2
            )
        )
    return targets


def service_targets(report: dict[str, Any]) -> list[Target]:
    """The service's targets, as service.py judged them (its ratios, in its order)."""
    scenarios = report["scenarios"]

    def scenario(suffix: str) -> dict[str, Any]:
        return next(s for s in scenarios if s["name"].endswith(suffix) and s["clients"] == 1)

    cold, cached = scenario("cold"), scenario("cached")
    up = next(s for s in scenarios if s["name"].startswith("unified-planning"))
    rows = [
        ("service cold vs UP, p50", f"{up['p50_s'] / cold['p50_s']:.1f}x faster ({ms(cold['p50_s'])})"),
        ("service repeated / cold, p50", f"{cached['p50_s'] / cold['p50_s']:.3f} ({ms(cached['p50_s'])})"),
    ]
    reference = f"UP OneshotPlanner p50 {ms(up['p50_s'])}"
    return [
        Target(name, measured, judged["goal"], reference, bool(judged["met"]))
        for (name, measured), judged in zip(rows, report["targets"], strict=True)
    ]


def cli_targets(report: dict[str, Any]) -> list[Target]:
    return [
        Target(
            "CLI whole process / UP script",
            f"{report['ratio']:.3f} ({ms(report['ours_median_s'])})",
            f"<= {report['target']}",
            f"UP script median {ms(report['up_median_s'])}",
            bool(report["met"]),
        )
    ]


def scale_targets(report: dict[str, Any]) -> list[Target]:
    targets = []
    for row in report["synthetic"]:
        limit = SCALE_TARGETS.get(row["parts"])
        if limit is None:
            continue
        ours, up = row["ours"]["median_s"], row["up"]["median_s"]
        reference = f"UP {up:.2f} s" if up is not None else f"UP: {row['up']['status']}"
        measured = f"{ours:.2f} s" if ours is not None else row["ours"]["status"]
        met = ours is not None and ours <= limit and bool(row["ours"]["valid"])
        targets.append(Target(f"scale: {row['parts']} synthetic parts", measured, f"<= {limit:g} s", reference, met))
    return targets


def batch_targets(report: dict[str, Any]) -> list[Target]:
    rate = report["fast_trials_per_s"]
    plain = report["plain_trials_per_s"]
    same = "same verdicts" if report["same_verdicts_on_sample"] else "DIFFERENT verdicts"
    targets = [
        Target(
            f"batch: {report['trials']} trials, VAL on",
            f"{rate:.0f} trials/s",
            f"{rate / plain:.0f}x the plain path",
            f"plain path {plain:.1f}/s, {same}",
            bool(report["same_verdicts_on_sample"]) and rate > plain,
        )
    ]
    if report.get("base_ratio") is not None:
        base_rate = rate / report["base_ratio"]
        targets.append(
            Target(
                "batch throughput / the base checkout's",
                f"{report['base_ratio']:.2f}",
                f">= {report['base_ratio_target']}",
                f"base {base_rate:.0f} trials/s" + ("" if report["same_verdicts_as_base"] else ", DIFFERENT verdicts"),
                report["base_ratio"] >= report["base_ratio_target"] and bool(report["same_verdicts_as_base"]),
            )
        )
    return targets


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer repetitions: a smoke run, not a measurement")
    parser.add_argument("--base", type=Path, help="a checkout of the code to compare with (planners and batch)")
    parser.add_argument("--no-service", action="store_true", help="skip benchmarks/service.py")
    args = parser.parse_args()
    base = ["--base", str(args.base)] if args.base else []
    run("planners.py", "--rounds", "8" if args.quick else "40", *base)
    if not args.no_service:
        run("service.py", *(["--quick"] if args.quick else []))
    run("cli.py", "--runs", "3" if args.quick else "7")
    run(
        "run.py",
        "--sizes",
        "80,160,320",
        "--repeat",
        "1" if args.quick else "3",
        "--output",
        str(RESULTS / "scale.json"),
    )
    run("batch.py", *(["--trials", "300", "--sample", "30", "--rounds", "1"] if args.quick else []), *base)
    targets = [
        *planner_targets(load("planners.json")),
        *([] if args.no_service else service_targets(load("service.json"))),
        *cli_targets(load("cli.json")),
        *scale_targets(load("scale.json")),
        *batch_targets(load("batch.json")),
    ]
    table = Table(
        "target", "measured", "goal", "reference (same run)", "met", title="Speed targets (ratios measured in this run)"
    )
    for target in targets:
        table.add_row(
            target.what,
            target.measured,
            target.target,
            target.reference,
            "[green]yes[/]" if target.met else "[red]NO[/]",
        )
    console = Console(width=140)
    console.print(table)
    met = all(target.met for target in targets)
    console.print(f"{sum(t.met for t in targets)} of {len(targets)} targets met" + ("" if met else " (see above)"))
    return 0 if met else 1


if __name__ == "__main__":
    sys.exit(main())
