"""How far the exact MDP scales: relevant parts 4 -> 16 and beyond, until it says too_large.

    python benchmarks/mdp.py [--sizes 4,6,...] [--seed 0] [--limit 10]

For each synthetic object it prints the parts that matter to the model (the MDP's restricted
search), the states it solved, its wall time, and the ratio against Fast Downward's optimal
planner (fd-opt) on the same task, timed in the same run. Each size runs twice: with every
fit certain (p = 1, where both must find plans of the same length) and with random fit
probabilities in [0.7, 1] (where only the MDP accounts for risk).
"""

from __future__ import annotations

import argparse
import dataclasses
import random
import statistics
import time

from rich.console import Console
from rich.table import Table

from causalplan.comparison.synthetic import synthetic_task
from causalplan.pddl.task import PlanningTask
from causalplan.planners import fd
from causalplan.planners.mdp import relevant_fits, solve_mdp
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanResult


def with_probabilities(task: PlanningTask, seed: int, certain: bool) -> PlanningTask:
    """Return the task with every fit certain, or with random probabilities in [0.7, 1]."""
    rng = random.Random(seed)
    fits = tuple(
        dataclasses.replace(fit, probability=1.0 if certain else round(rng.uniform(0.7, 1.0), 2))
        for fit in task.obj.fits
    )
    return dataclasses.replace(task, obj=dataclasses.replace(task.obj, fits=fits))


def fresh_plan(task: PlanningTask, planner: str) -> PlanResult:
    """Plan without Fast Downward's answer cache, so every timed run is a real solve."""
    fd.clear_solve_cache()
    return plan_task(task, planner, 60.0)


def timed(function, repeat: int):  # type: ignore[no-untyped-def]
    """Return the last result of ``function()`` and the median wall time of ``repeat`` calls."""
    times, result = [], None
    for _ in range(repeat):
        started = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - started)
    return result, statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="4,6,8,10,12,16,20,24,28,32,40")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--limit", type=float, default=10.0, help="the MDP's time limit, seconds")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    console = Console(width=160)
    table = Table(
        "parts",
        "relevant parts/fits",
        "fits p",
        "status",
        "states",
        "MDP",
        "fd-opt",
        "MDP/fd-opt",
        "length MDP/fd-opt",
        "P(success) MDP/fd-opt",
        title=f"Exact MDP scaling (synthetic objects, seed {args.seed}, medians of {args.repeat})",
    )
    first_too_large: int | None = None
    largest_solved = 0
    for size in (int(item) for item in args.sizes.split(",")):
        base = synthetic_task(size, args.seed)
        fits = relevant_fits(base)
        parts = {part for fit in fits for part in (fit.moving_part, fit.fixed_part)}
        for certain in (True, False):
            task = with_probabilities(base, args.seed + size, certain)
            solution, mdp_seconds = timed(lambda task=task: solve_mdp(task, args.limit), args.repeat)
            optimal, fd_seconds = timed(lambda task=task: fresh_plan(task, "fd-opt"), 1 if not certain else args.repeat)
            status = solution.status.value
            if status == "solved":
                largest_solved = max(largest_solved, len(parts))
            elif status == "too_large" and first_too_large is None:
                first_too_large = len(parts)
            mdp_probability = "-" if solution.success_probability is None else f"{solution.success_probability:.3f}"
            fd_probability = "-" if optimal.success_probability is None else f"{optimal.success_probability:.3f}"
            mdp_length = len(solution.actions) if solution.actions else "-"
            fd_length = len(optimal.steps) if optimal.has_plan else "-"
            table.add_row(
                str(size),
                f"{len(parts)} / {len(fits)}",
                "1" if certain else "0.7-1",
                status,
                f"{solution.states:,}",
                f"{mdp_seconds * 1000:.1f} ms",
                f"{fd_seconds * 1000:.1f} ms",
                f"{mdp_seconds / fd_seconds:.2f}x",
                f"{mdp_length} / {fd_length}",
                f"{mdp_probability} / {fd_probability}",
            )
    console.print(table)
    console.print(
        f"Largest number of relevant parts solved exactly: {largest_solved} (target: at least 16); "
        f"first too_large at {first_too_large if first_too_large is not None else 'none of these sizes'} "
        "relevant parts."
    )


if __name__ == "__main__":
    main()
