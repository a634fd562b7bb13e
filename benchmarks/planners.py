"""The planner's own speed: cold and repeated solves against unified-planning, and the older code.

    python benchmarks/planners.py [--rounds 40] [--base CHECKOUT] [--gap 0.02]

On the paper's four tasks in turn (the desk-lamp model on the desk lamp and, through its
mapping, on the flashlight; the candle model on the candle and the kerosene lamp):

- in this process, interleaved task by task: ``plan_task(task, "fd")`` cold (FD's answers and
  VAL's verdicts forgotten first, as for a model never seen), cold with ``val=True`` (as the
  CLI plans), repeated (the answer kept: what a repeated request costs), and the reference,
  unified-planning's ``OneshotPlanner("fast-downward")`` on the same task;
- in fresh processes, a round of cold solves each, interleaved: ours with a search process
  started ahead (``fd.prestart``, as a service worker does) and without, and with ``--base
  CHECKOUT`` (e.g. ``git worktree add /tmp/base 96c4986``) the older code likewise. This is
  what a prestarted search buys, and the cold path the targets use (a worker's).

``--gap`` seconds pass before each solve, as between requests, so a search started ahead has
time to be ready. Results: benchmarks/results/planners.json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from causalplan.pddl.task import PlanningTask

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
PAPER_CASES = (
    ("paper/desk_lamp.yaml", None),
    ("paper/desk_lamp.yaml", "paper/flashlight_mapping.yaml"),
    ("near/candle.yaml", None),
    ("near/candle.yaml", "near/kerosene_lamp_mapping.yaml"),
)
COLD_VS_UP = 10.0
"""The cold p50 must be at least this many times faster than unified-planning's."""
REPEATED_VS_COLD = 0.3
"""A repeated solve's p50 must be at most this fraction of the cold p50."""

SCRIPT = """
import json, sys, time
from pathlib import Path
from causalplan.inputs import load_mapping, load_model
from causalplan.objects.catalog import load_catalog
from causalplan.pddl.task import build_task
from causalplan.planners.pipeline import plan_task

try:
    from causalplan.planners import fd
    if sys.argv[5] == "1":
        fd.prestart(fd.CONFIGS["fd"])
except ImportError:  # the code before planners/fd/ (it reads CAUSALPLAN_SEARCH_PRESTART)
    from causalplan.planners import fast_downward as fd
    fd.prestart()
try:
    from causalplan.caches import fresh as forget_answers
except ImportError:  # the code before causalplan/caches.py
    forget_answers = fd.clear_solve_cache

examples, cases, rounds, gap = Path(sys.argv[1]), json.loads(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
catalog = load_catalog()
tasks = []
for model_path, mapping_path in cases:
    model = load_model(examples / model_path, catalog).model
    mapping = load_mapping(examples / mapping_path, catalog).mapping if mapping_path else None
    tasks.append(build_task(model, catalog.get((mapping or model.labelling).object_id), mapping))
for task in tasks:
    plan_task(task, "fd")
seconds = []
for index in range(rounds * len(tasks)):
    forget_answers()
    time.sleep(gap)
    started = time.perf_counter()
    assert plan_task(tasks[index % len(tasks)], "fd").has_plan
    seconds.append(time.perf_counter() - started)
print(json.dumps(seconds))
"""


def paper_tasks() -> list[PlanningTask]:
    from causalplan.inputs import load_mapping, load_model
    from causalplan.objects.catalog import load_catalog
    from causalplan.pddl.task import build_task

    catalog = load_catalog()
    tasks = []
    for model_path, mapping_path in PAPER_CASES:
        model = load_model(EXAMPLES / model_path, catalog).model
        mapping = load_mapping(EXAMPLES / mapping_path, catalog).mapping if mapping_path else None
        assert model is not None and (mapping_path is None or mapping is not None)
        tasks.append(build_task(model, catalog.get((mapping or model.labelling).object_id), mapping))
    return tasks


def fresh_cold(checkout: Path | None, rounds: int, gap: float, prestart: bool) -> list[float]:
    """Return cold solve times in a fresh process: of this code, or of ``checkout``'s."""
    flag = "1" if prestart else "0"
    environment = {**os.environ, "CAUSALPLAN_SEARCH_PRESTART": flag}
    if checkout is not None:
        environment["PYTHONPATH"] = str(checkout)
    arguments = [str(EXAMPLES), json.dumps(PAPER_CASES), str(rounds), str(gap), flag]
    command = [sys.executable, "-c", SCRIPT, *arguments]
    completed = subprocess.run(
        command, cwd=checkout or ROOT, env=environment, check=True, capture_output=True, text=True
    )
    seconds: list[float] = json.loads(completed.stdout.strip().splitlines()[-1])
    return seconds


def p50(values: list[float]) -> float:
    return statistics.median(values)


def ms(seconds: float) -> str:
    return f"{seconds * 1000:.2f} ms"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=40, help="rounds over the four tasks")
    parser.add_argument("--base", type=Path, help="a checkout of the older code, measured in the same run")
    parser.add_argument("--gap", type=float, default=0.02, help="seconds between solves, as between requests")
    parser.add_argument("--output", type=Path, default=ROOT / "benchmarks" / "results" / "planners.json")
    args = parser.parse_args()
    from causalplan import caches
    from causalplan.planners.pipeline import plan_task
    from causalplan.planners.up_problem import solve_with_up

    tasks = paper_tasks()
    for task in tasks:  # warm-up: imports, the translator, UP's engine
        assert plan_task(task, "fd", val=True).has_plan
        assert solve_with_up(task, "fast-downward").actions
    kinds = ("cold", "cold with VAL", "repeated", "unified-planning")
    times: dict[str, list[float]] = {kind: [] for kind in kinds}
    for _ in range(args.rounds):
        for task in tasks:
            for kind in kinds:
                if kind.startswith("cold"):
                    caches.fresh()
                time.sleep(args.gap)
                started = time.perf_counter()
                if kind == "unified-planning":
                    assert solve_with_up(task, "fast-downward").actions
                else:
                    assert plan_task(task, "fd", val=kind == "cold with VAL").has_plan
                times[kind].append(time.perf_counter() - started)
    fresh_rounds = max(1, args.rounds // 4)  # each round starts processes of its own
    checkouts: dict[str, Path | None] = {"ours": None}
    if args.base:
        checkouts["base"] = args.base.resolve()
    fresh: dict[str, list[float]] = {}
    for _ in range(fresh_rounds):
        for name, checkout in checkouts.items():
            for prestart in (True, False):
                label = f"{name}, fresh process, prestart {'on' if prestart else 'off'}"
                fresh.setdefault(label, []).extend(fresh_cold(checkout, 1, args.gap, prestart))
    worker_cold = p50(fresh["ours, fresh process, prestart on"])
    repeated, up = p50(times["repeated"]), p50(times["unified-planning"])
    for kind, values in [*times.items(), *fresh.items()]:
        print(f"{kind:>40}: p50 {ms(p50(values))}, p95 {ms(sorted(values)[int(0.95 * len(values))])}")
    print(f"unified-planning / cold (a worker's: prestart on): {up / worker_cold:.1f}x (target >= {COLD_VS_UP:g}x)")
    print(f"unified-planning / cold (in process, no prestart): {up / p50(times['cold']):.1f}x")
    print(f"repeated / cold: {repeated / worker_cold:.3f} (target <= {REPEATED_VS_COLD})")
    shares = {}
    for name in checkouts:
        on, off = p50(fresh[f"{name}, fresh process, prestart on"]), p50(fresh[f"{name}, fresh process, prestart off"])
        shares[name] = (off - on) / off
        print(f"prestart buys {shares[name]:.1%} of {name}'s cold path (kept only if >= 20%)")
    report: dict[str, object] = {
        "rounds": args.rounds,
        "fresh_rounds": fresh_rounds,
        "gap_s": args.gap,
        "base": str(args.base) if args.base else None,
        "p50_s": {kind: p50(values) for kind, values in [*times.items(), *fresh.items()]},
        "seconds": {**times, **fresh},
        "up_over_cold": up / worker_cold,
        "repeated_over_cold": repeated / worker_cold,
        "prestart_share_of_cold": shares,
        "cold_met": up / worker_cold >= COLD_VS_UP,
        "repeated_met": repeated / worker_cold <= REPEATED_VS_COLD,
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    return 0 if report["cold_met"] and report["repeated_met"] else 1


if __name__ == "__main__":
    sys.exit(main())
