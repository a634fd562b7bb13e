"""How long the exact troubleshooting solver takes: per catalog object, and as objects grow.

    python benchmarks/troubleshoot.py [--rounds 5] [--limit-seconds 60] [--gap 0.05]

1. Each catalog object with its reference model: the time to make the strategies' table
   (``troubleshooting_task(obj, model).table()``: three exact policies and every fault's
   episode), against one cold plan of the same model in this process (``plan_task(task, "fd",
   val=True)`` after ``caches.fresh()``, as `causalplan plan` plans), interleaved; medians.
   Target: the table takes at most as long as the plan (ratio <= 1).
2. Synthetic objects of growing size, the two extremes of access (``troubleshoot.synthetic``):
   a star (every part on the base: 2^k assembly states) and a chain (each part on the one
   below), faults hidden, uniform prior (every part suspected: the most beliefs). One solve
   per size, up to the first that is refused (``troubleshooting_too_large``) or takes longer
   than ``--limit-seconds``: where exact solving stops.
"""

from __future__ import annotations

import argparse
import statistics
import time

from causalplan import caches
from causalplan.causal.documents import SourceMap
from causalplan.inputs import model_from_data
from causalplan.objects.catalog import load_catalog
from causalplan.objects.reference import reference_model
from causalplan.pddl.task import build_task
from causalplan.planners.pipeline import plan_task
from causalplan.troubleshoot.errors import TooLargeError
from causalplan.troubleshoot.priors import Suspicion
from causalplan.troubleshoot.solver import solve
from causalplan.troubleshoot.synthetic import chain, star
from causalplan.troubleshoot.task import troubleshooting_task

TABLE_VS_PLAN = 1.0
"""The table of one catalog object must take at most this many times one cold plan."""


def catalog_rows(rounds: int, gap: float) -> list[tuple[str, float, float]]:
    """Return (object, table ms, plan ms) medians for every catalog object."""
    catalog = load_catalog()
    rows = []
    for obj in catalog.objects.values():
        loaded = model_from_data(reference_model(obj), SourceMap(), catalog)
        assert loaded.model is not None and loaded.is_valid, obj.id
        model = loaded.model
        tables, plans = [], []
        for _ in range(rounds):
            time.sleep(gap)  # the plan's search processes settle before the next measure
            started = time.perf_counter()
            troubleshooting_task(obj, model).table()
            tables.append(time.perf_counter() - started)
            caches.fresh()
            time.sleep(gap)
            started = time.perf_counter()
            result = plan_task(build_task(model, obj), "fd", val=True)
            plans.append(time.perf_counter() - started)
            assert result.has_plan, obj.id
        rows.append((obj.id, 1000 * statistics.median(tables), 1000 * statistics.median(plans)))
    return rows


def scaling_rows(shape: str, limit_seconds: float) -> list[tuple[int, int, int, float, str]]:
    """Return (parts on the base, assembly states, beliefs, seconds, outcome) per size until exact solving stops."""
    build = star if shape == "star" else chain
    rows = []
    for count in range(2, 40):
        structure = build(count, visible=False)
        suspicion = Suspicion("uniform", (1.0,) * structure.size)
        started = time.perf_counter()
        try:
            policy = solve(structure, suspicion)
        except TooLargeError as exc:
            rows.append((count, 0, 0, time.perf_counter() - started, f"refused: {exc.code}"))
            break
        seconds = time.perf_counter() - started
        rows.append((count, len(policy.graph.states), policy.beliefs_solved, seconds, "exact"))
        if seconds > limit_seconds:
            break
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--limit-seconds", type=float, default=60.0)
    parser.add_argument("--gap", type=float, default=0.05, help="Seconds to wait before each measure.")
    args = parser.parse_args()

    print("catalog objects, reference model (medians of", args.rounds, "rounds)")
    print(f"{'object':<15} {'table ms':>9} {'plan ms':>9} {'ratio':>6}")
    worst = 0.0
    for object_id, table_ms, plan_ms in catalog_rows(args.rounds, args.gap):
        ratio = table_ms / plan_ms
        worst = max(worst, ratio)
        print(f"{object_id:<15} {table_ms:>9.1f} {plan_ms:>9.1f} {ratio:>6.2f}")
    verdict = "met" if worst <= TABLE_VS_PLAN else "NOT met"
    print(f"worst table/plan ratio {worst:.2f} (target <= {TABLE_VS_PLAN:g}: {verdict})")
    for shape in ("star", "chain"):
        print(f"\nsynthetic {shape}, hidden faults, uniform prior")
        print(f"{'parts':>5} {'assembly states':>15} {'beliefs':>8} {'seconds':>8}  outcome")
        for count, states, beliefs, seconds, outcome in scaling_rows(shape, args.limit_seconds):
            print(f"{count:>5} {states:>15} {beliefs:>8} {seconds:>8.2f}  {outcome}")


if __name__ == "__main__":
    main()
