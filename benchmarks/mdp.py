"""The MDP at scale: heuristic search (LAO*, planner ``mdp``) against the exact solver and fd-opt.

    python benchmarks/mdp.py [--sizes 4,8,...] [--seed 0] [--limit 30] [--exact-limit 10]

Both MDP solvers run as the planners do (``objective.solve_for``: the most reliable policy,
the step cost only breaking ties). For each synthetic object, with random fit probabilities
in [0.7, 1], it prints the parts and fits that matter to the model; for the heuristic search
(at the planner's default time limit) its status, states expanded, wall time, and success
probability with its bounds when the limit came first; for the exact solver (where it runs)
its states and time; and Fast Downward's optimal planner (fd-opt) on the same task, timed in
the same run, as the reference. Ratios are exact against heuristic (states, time) and
heuristic against fd-opt (time). It ends with the largest number of relevant parts solved to
proved optimality, and with bounds.
"""

from __future__ import annotations

import argparse
import dataclasses
import random
import time
from collections.abc import Callable
from typing import TypeVar

from rich.console import Console
from rich.table import Table

from causalplan import caches
from causalplan.comparison.synthetic import synthetic_task
from causalplan.pddl.task import PlanningTask
from causalplan.planners.fd.solve import DEFAULT_TIME_LIMIT
from causalplan.planners.mdp import Optimality, relevant_fits
from causalplan.planners.mdp.objective import solve_for
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanResult, PlanStatus

T = TypeVar("T")


def with_probabilities(task: PlanningTask, seed: int) -> PlanningTask:
    """Return the task with random fit probabilities in [0.7, 1]."""
    rng = random.Random(seed)
    fits = tuple(dataclasses.replace(fit, probability=round(rng.uniform(0.7, 1.0), 2)) for fit in task.obj.fits)
    return dataclasses.replace(task, obj=dataclasses.replace(task.obj, fits=fits))


def fresh_plan(task: PlanningTask, planner: str) -> PlanResult:
    """Plan without Fast Downward's answer cache, so every timed run is a real solve."""
    caches.current().fd_answers.clear()
    return plan_task(task, planner, 60.0, val=False)


def timed(function: Callable[[], T]) -> tuple[T, float]:
    """Return ``function()`` and its wall time."""
    started = time.perf_counter()
    result = function()
    return result, time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="4,8,12,16,20,24,28,40,80,120,200,280")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--limit", type=float, default=DEFAULT_TIME_LIMIT, help="the heuristic MDP's time limit")
    parser.add_argument("--exact-limit", type=float, default=10.0, help="the exact MDP's time limit")
    args = parser.parse_args()
    console = Console(width=200)
    table = Table(
        "parts",
        "relevant parts/fits",
        "mdp status",
        "expanded",
        "mdp time",
        "P(success) [bounds]",
        "mdp-exact",
        "exact states",
        "exact time",
        "states exact/mdp",
        "time exact/mdp",
        "fd-opt time",
        "mdp/fd-opt time",
        title=f"MDP at scale: fits p in [0.7, 1] (synthetic objects, seed {args.seed}; "
        f"mdp limit {args.limit:g} s, exact {args.exact_limit:g} s)",
    )
    largest_optimal = largest_bounded = 0
    for size in (int(item) for item in args.sizes.split(",")):
        task = with_probabilities(synthetic_task(size, args.seed), args.seed + size)
        fits = relevant_fits(task)
        parts = len({part for fit in fits for part in (fit.moving_part, fit.fixed_part)})
        heuristic, heuristic_seconds = timed(lambda task=task: solve_for(task, args.limit))  # type: ignore[misc]
        exact, exact_seconds = timed(lambda task=task: solve_for(task, args.exact_limit, exact=True))  # type: ignore[misc]
        optimal, fd_seconds = timed(lambda task=task: fresh_plan(task, "fd-opt"))  # type: ignore[misc]
        probability = "-"
        if heuristic.status is PlanStatus.SOLVED and heuristic.success_probability is not None:
            probability = f"{heuristic.success_probability:.4g}"
            if heuristic.optimality is Optimality.BOUNDED:
                probability += f" [{heuristic.success_probability:.4g}, {heuristic.success_upper:.4g}]"
                largest_bounded = max(largest_bounded, parts)
            else:
                largest_optimal = max(largest_optimal, parts)
        exact_ran = exact.status is PlanStatus.SOLVED
        if exact_ran and heuristic.optimality is Optimality.OPTIMAL:
            assert exact.success_probability is not None and heuristic.success_probability is not None
            assert abs(exact.success_probability - heuristic.success_probability) < 1e-9
        table.add_row(
            str(size),
            f"{parts} / {len(fits)}",
            f"{heuristic.status.value} ({heuristic.optimality.value})",
            f"{heuristic.states:,}",
            f"{heuristic_seconds:.2f} s",
            probability,
            exact.status.value,
            f"{exact.states:,}",
            f"{exact_seconds:.2f} s",
            f"{exact.states / max(1, heuristic.states):.1f}x" if exact_ran else "-",
            f"{exact_seconds / heuristic_seconds:.2f}x" if exact_ran else "-",
            f"{fd_seconds * 1000:.0f} ms" + ("" if optimal.has_plan else f" ({optimal.status.value})"),
            f"{heuristic_seconds / fd_seconds:.1f}x",
        )
    console.print(table)
    console.print(
        f"Largest number of relevant parts solved to proved optimality by mdp: {largest_optimal}; "
        f"largest answered with bounds (anytime) within the limit: {largest_bounded or 'none'} "
        "(goal: 80 relevant parts solved)."
    )


if __name__ == "__main__":
    main()
