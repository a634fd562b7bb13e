"""Issue 8's speed targets in one command: service, CLI, scale and batch, each against its reference.

    python benchmarks/speed.py [--quick]

Runs the four benchmarks below one after another, each as its own process (so none is slowed
by another's imports or caches), shows their own output, and ends with one table: every
target, what was measured, the reference measured in the same run, and whether it is met.

- ``benchmarks/service.py``: POST /v1/plans on a real server, cold (a model it has not seen,
  FD's answer cache off) and repeated; reference: unified-planning's OneshotPlanner.
- ``benchmarks/cli.py``: ``causalplan plan examples/paper/desk_lamp.yaml`` as a whole process;
  reference: a script doing the same solve through unified-planning.
- ``benchmarks/run.py --sizes 80,160,320``: synthetic assemblies; reference: the same tasks
  through unified-planning (axiom-free formulation, its Fast Downward engine).
- ``benchmarks/batch.py``: 1,000 simulated participants' trials through ``causalplan batch``;
  reference: the plain path, one trial at a time with every cache emptied.

The exit code is 0 when every target is met, 1 otherwise. Results: benchmarks/results/*.json.
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


def service_targets(report: dict[str, Any]) -> list[Target]:
    """The service's four targets, as service.py judged them (its goals and verdicts, in its order)."""
    scenarios = report["scenarios"]

    def scenario(suffix: str) -> dict[str, Any]:
        return next(s for s in scenarios if s["name"].endswith(suffix) and s["clients"] == 1)

    cold, cached = scenario("cold"), scenario("cached")
    up = next(s for s in scenarios if s["name"].startswith("unified-planning"))
    reference = f"UP OneshotPlanner p50 {ms(up['p50_s'])}"
    rows = [
        ("service cold, p50 (1 client)", ms(cold["p50_s"]), reference),
        ("service cold, p95 (1 client)", ms(cold["p95_s"]), reference),
        ("service cold vs UP", f"{up['p50_s'] / cold['p50_s']:.1f}x faster", reference),
        ("service repeated request, p50", ms(cached["p50_s"]), "the cold p50 above"),
    ]
    return [
        Target(name, measured, judged["goal"], against, bool(judged["met"]))
        for (name, measured, against), judged in zip(rows, report["targets"], strict=True)
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
    return [
        Target(
            f"batch: {report['trials']} trials",
            f"{rate:.0f} trials/s",
            f">= {report['target_trials_per_s']:.0f}/s",
            f"plain path {plain:.1f}/s ({rate / plain:.0f}x), {same}",
            bool(report["met"]),
        )
    ]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer repetitions: a smoke run, not a measurement")
    args = parser.parse_args()
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
    run("batch.py", *(["--trials", "300", "--sample", "30"] if args.quick else []))
    targets = [
        *service_targets(load("service.json")),
        *cli_targets(load("cli.json")),
        *scale_targets(load("scale.json")),
        *batch_targets(load("batch.json")),
    ]
    table = Table("target", "measured", "goal", "reference (same run)", "met", title="Issue 8: speed targets")
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
