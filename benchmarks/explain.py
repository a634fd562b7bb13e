"""Explanation speed: a why-not answer against a plan request, a repair search against a transfer verdict.

    python benchmarks/explain.py [--rounds 7]

In one process, every measurement cold (FD's answers, VAL's verdicts and the simulations
forgotten before each), medians over ``--rounds``:

* a why-not answer (``explain_plan`` with the question: the plan, then the alternative plan
  with the question's constraint, both replayed and checked by VAL) on the paper's failed
  desk-lamp model, for three questions, against ``plan_task(task, "fd", val=True)``, the plan
  request. Target: at most 3x.
* a repair search (``search_repairs``: every edit set of size 1 and 2, each re-checked by a
  full verdict with VAL and the simulator) on the paper's failed flashlight mapping, against
  one full transfer verdict (planner, VAL, simulator) of the paper's working desk-lamp model on
  the flashlight. Target: at most 50x. The failed mapping's own verdict is decided by the
  precheck without planning; its time is printed too, as a second reference.

Prints a table and the targets; exit 0 when both are met.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from causalplan import caches  # noqa: E402
from causalplan.causal.model import CausalModel, Labelling  # noqa: E402
from causalplan.explain.explanation import explain_plan  # noqa: E402
from causalplan.explain.repair import search_repairs  # noqa: E402
from causalplan.inputs import load_mapping, load_model  # noqa: E402
from causalplan.objects.catalog import Catalog, load_catalog  # noqa: E402
from causalplan.pddl.task import build_task, catalog_task  # noqa: E402
from causalplan.planners.pipeline import plan_task  # noqa: E402
from causalplan.transfer.verdict import evaluate_transfer  # noqa: E402

WHY_NOT_TARGET = 3.0
REPAIR_TARGET = 50.0
QUESTIONS = ("shade before light_bulb", "leave out the shade", "leave out step 1")
PAPER = ROOT / "examples" / "paper"


def cold_median(action: Callable[[], object], rounds: int) -> float:
    """Return the median seconds of ``action`` with every cache emptied before each run."""
    times = []
    for _ in range(rounds):
        caches.fresh()
        started = time.perf_counter()
        action()
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def _model(name: str, catalog: Catalog) -> CausalModel:
    loaded = load_model(PAPER / name, catalog)
    assert loaded.model is not None
    return loaded.model


def _mapping(name: str, catalog: Catalog) -> Labelling:
    loaded = load_mapping(PAPER / name, catalog)
    assert loaded.mapping is not None
    return loaded.mapping


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=7)
    rounds = parser.parse_args().rounds
    catalog = load_catalog(())
    failed = _model("failed_desk_lamp.yaml", catalog)
    task = build_task(failed, catalog.get("desk_lamp"))
    plan_task(task, "fd", val=True)  # warm imports: the translator, VAL's binary found
    explain_plan(task, None, QUESTIONS[0], simulate=False)

    plan_seconds = cold_median(lambda: plan_task(task, "fd", val=True), rounds)
    rows: list[tuple[str, float, float | None]] = [("plan request (plan_task fd, VAL)", plan_seconds, None)]
    why_not_ratios = []
    for question in QUESTIONS:
        seconds = cold_median(lambda q=question: explain_plan(task, None, q), rounds)  # type: ignore[misc]
        why_not_ratios.append(seconds / plan_seconds)
        rows.append((f"why not '{question}'", seconds, seconds / plan_seconds))

    model, working = _model("desk_lamp.yaml", catalog), _mapping("flashlight_mapping.yaml", catalog)
    failed_mapping = _mapping("failed_flashlight_mapping.yaml", catalog)
    catalog_task(model, catalog, working)
    evaluate_transfer(model, working, catalog, "fd", val=True)  # warm: PyBullet imported
    verdict_seconds = cold_median(lambda: evaluate_transfer(model, working, catalog, "fd", val=True), rounds)
    precheck_seconds = cold_median(lambda: evaluate_transfer(failed, failed_mapping, catalog, "fd", val=True), rounds)
    search = search_repairs(failed, failed_mapping, catalog)
    repair_seconds = cold_median(lambda: search_repairs(failed, failed_mapping, catalog), max(3, rounds // 2))
    rows += [
        ("transfer verdict, full (desk lamp -> flashlight)", verdict_seconds, None),
        ("transfer verdict, precheck (failed mapping)", precheck_seconds, None),
        (
            f"repair search (failed mapping; {search.checked} edit sets)",
            repair_seconds,
            repair_seconds / verdict_seconds,
        ),
    ]
    print("| measurement | median ms (cold) | ratio to its reference |")
    print("|---|---|---|")
    for name, seconds, ratio in rows:
        print(f"| {name} | {seconds * 1000:.3f} | {'' if ratio is None else f'{ratio:.2f}x'} |")
    worst = max(why_not_ratios)
    repair_ratio = repair_seconds / verdict_seconds
    met_why = worst <= WHY_NOT_TARGET
    met_repair = repair_ratio <= REPAIR_TARGET
    verdict_words = "met" if met_why else "MISSED"
    print(f"why-not answer / plan request: worst {worst:.2f}x (target <= {WHY_NOT_TARGET:g}x): {verdict_words}")
    print(
        f"repair search / full transfer verdict: {repair_ratio:.1f}x (target <= {REPAIR_TARGET:g}x): "
        f"{'met' if met_repair else 'MISSED'}; {len(search.repairs)} repairs found; "
        f"{repair_seconds / precheck_seconds:.0f}x the precheck verdict"
    )
    return 0 if met_why and met_repair else 1


if __name__ == "__main__":
    sys.exit(main())
