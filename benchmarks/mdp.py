"""The MDP at scale: planner ``mdp`` against the exact solver and fd-opt, and against closed forms.

    python benchmarks/mdp.py [--sizes 4,8,...] [--seed 0] [--limit 30] [--exact-limit 10] [--no-families] [--no-bounds]

Both MDP solvers run as the planners do (``objective.solve_for``: the most reliable policy,
the step cost only breaking ties). For each synthetic object, with random fit probabilities
in [0.7, 1], it prints the parts and fits that matter to the model; for ``mdp`` (at the
planner's default time limit) its status, how it proved the optimum or where it stopped, the
states it expanded or solved (search states, components' states, residual groups), wall time,
and success probability with its bounds when the limit came first; for the exact solver
(where it runs) its states and time; and Fast Downward's optimal planner (fd-opt) on the
same task, timed in the same run, as the reference. Then the families whose optimum is known
in closed form (``comparison/families.py``), 80 relevant parts and more, with the distance
to it. Then the plain search's expansions until it closes with the bound counting each shared
holder once against the earlier bound (shared holders counted nowhere), on the rows where it
closes. It ends with the largest number of relevant parts solved to proved optimality, and
with bounds.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import TypeVar

from rich.console import Console
from rich.table import Table

from causalplan import caches
from causalplan.comparison.families import (
    cyclic_components,
    independent_components,
    riskiest_first_chains,
    uncertain_tree,
    with_probabilities,
)
from causalplan.comparison.synthetic import synthetic_task
from causalplan.pddl.task import PlanningTask
from causalplan.planners.fd.solve import DEFAULT_TIME_LIMIT
from causalplan.planners.mdp import MdpSolution, Optimality, relevant_fits
from causalplan.planners.mdp.composed import ComposedPolicy
from causalplan.planners.mdp.model import compile_mdp
from causalplan.planners.mdp.objective import solve_for
from causalplan.planners.mdp.search import search_compiled_mdp, tie_breaking_step_cost
from causalplan.planners.mdp.split_solve import SplitPolicy
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanResult, PlanStatus

T = TypeVar("T")


def fresh_plan(task: PlanningTask, planner: str) -> PlanResult:
    """Plan without Fast Downward's answer cache, so every timed run is a real solve."""
    caches.current().fd_answers.clear()
    return plan_task(task, planner, 60.0, val=False)


def timed(function: Callable[[], T]) -> tuple[T, float]:
    """Return ``function()`` and its wall time."""
    started = time.perf_counter()
    result = function()
    return result, time.perf_counter() - started


def how(solution: MdpSolution) -> str:
    """Return how the answer was proved (by the policy it returns), or where it stopped."""
    if solution.status is not PlanStatus.SOLVED or solution.optimality is Optimality.BOUNDED:
        return "time limit"
    if isinstance(solution.decider, ComposedPolicy):
        return f"{len(solution.decider.solved)} components"
    if isinstance(solution.decider, SplitPolicy):
        return "split after each attempt"
    if not solution.fewest_attempts:  # the search stopped when its bounds met, before it closed
        return "bounds met"
    return "search closed"


def relevant_parts(task: PlanningTask) -> tuple[int, int]:
    """Return the parts (the base included, as in earlier entries) and the fits that matter to the model."""
    fits = relevant_fits(task)
    return len({part for fit in fits for part in (fit.moving_part, fit.fixed_part)}), len(fits)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="4,8,12,16,20,24,28,40,80,120,200,280")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--limit", type=float, default=DEFAULT_TIME_LIMIT, help="the MDP's time limit")
    parser.add_argument("--exact-limit", type=float, default=10.0, help="the exact MDP's time limit")
    parser.add_argument("--no-families", action="store_true", help="leave out the closed-form families")
    parser.add_argument("--no-bounds", action="store_true", help="leave out the bound's before/after expansions")
    args = parser.parse_args()
    console = Console(width=220)
    table = Table(
        "parts",
        "relevant parts/fits",
        "mdp status",
        "proved by / stopped at",
        "states",
        "mdp time",
        "P(success) [bounds]",
        "mdp-exact",
        "exact states",
        "exact time",
        "time exact/mdp",
        "fd-opt time",
        "mdp/fd-opt time",
        title=f"MDP at scale: fits p in [0.7, 1] (synthetic objects, seed {args.seed}; "
        f"mdp limit {args.limit:g} s, exact {args.exact_limit:g} s)",
    )
    largest_optimal = largest_bounded = 0
    for size in (int(item) for item in args.sizes.split(",")):
        task = with_probabilities(synthetic_task(size, args.seed), args.seed + size)
        parts, fits = relevant_parts(task)
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
        elif heuristic.success_upper is not None:
            probability = f"- [0, {heuristic.success_upper:.4g}]"
        exact_ran = exact.status is PlanStatus.SOLVED
        if exact_ran and heuristic.optimality is Optimality.OPTIMAL:
            assert exact.success_probability is not None and heuristic.success_probability is not None
            assert abs(exact.success_probability - heuristic.success_probability) < 1e-9
        table.add_row(
            str(size),
            f"{parts} / {fits}",
            f"{heuristic.status.value} ({heuristic.optimality.value})",
            how(heuristic),
            f"{heuristic.states:,}",
            f"{heuristic_seconds:.2f} s",
            probability,
            exact.status.value,
            f"{exact.states:,}",
            f"{exact_seconds:.2f} s",
            f"{exact_seconds / heuristic_seconds:.2f}x" if exact_ran else "-",
            f"{fd_seconds * 1000:.0f} ms" + ("" if optimal.has_plan else f" ({optimal.status.value})"),
            f"{heuristic_seconds / fd_seconds:.1f}x",
        )
    console.print(table)
    if not args.no_families:
        families(console, args.limit)
    if not args.no_bounds:
        bound_expansions(console, args.seed, args.limit)
    console.print(
        f"Largest number of relevant parts of a synthetic object solved to proved optimality by mdp: "
        f"{largest_optimal}; largest answered with bounds (anytime) within the limit: {largest_bounded or 'none'} "
        "(goal: 80 relevant parts solved)."
    )


def families(console: Console, limit: float) -> None:
    """Print ``mdp`` on the families with closed-form optima (and a tree with 15 uncertain fits, which has none)."""
    table = Table(
        "family",
        "relevant parts/fits",
        "mdp status",
        "proved by / stopped at",
        "states",
        "mdp time",
        "P(success)",
        "|P - closed form|",
        "E[attempts]",
        "|E - closed form|",
        title=f"Families with known optima, 80 relevant parts and more (mdp limit {limit:g} s)",
    )
    rows = [
        ("16 components of 5 (OR, shared socket, two plugs)", independent_components(16)),
        ("16 rings of 4 contacts on shared sockets", cyclic_components(16, 1)),
        ("16 chains of 5, riskiest first", riskiest_first_chains(16, 5)),
        ("20 chains of 5, riskiest first", riskiest_first_chains(20, 5)),
    ]
    for name, family in rows:
        solution, seconds = timed(lambda family=family: solve_for(family.task, limit))  # type: ignore[misc]
        parts, fits = relevant_parts(family.task)
        success, attempts = solution.success_probability, solution.expected_actions
        table.add_row(
            name,
            f"{parts} / {fits}",
            f"{solution.status.value} ({solution.optimality.value})",
            how(solution),
            f"{solution.states:,}",
            f"{seconds:.2f} s",
            f"{success:.6g}" if success is not None else "-",
            f"{abs(success - family.success_probability):.1e}" if success is not None else "-",
            f"{attempts:.4f}" if attempts is not None else "-",
            f"{abs(attempts - family.expected_attempts):.1e}"
            if attempts is not None and family.expected_attempts is not None
            else "-",
        )
    for seed in range(4):
        task = uncertain_tree(80, 15, seed)
        solution, seconds = timed(lambda task=task: solve_for(task, limit))  # type: ignore[misc]
        parts, fits = relevant_parts(task)
        success = solution.success_probability
        bounds = f" [{success:.4g}, {solution.success_upper:.4g}]" if solution.optimality is Optimality.BOUNDED else ""
        table.add_row(
            f"80-part tree, 15 uncertain fits (seed {seed})",
            f"{parts} / {fits}",
            f"{solution.status.value} ({solution.optimality.value})",
            how(solution),
            f"{solution.states:,}",
            f"{seconds:.2f} s",
            (f"{success:.6g}" if success is not None else "-") + bounds,
            "(no closed form)",
            f"{solution.expected_actions:.4f}" if solution.expected_actions is not None else "-",
            "-",
        )
    console.print(table)


def bound_expansions(console: Console, seed: int, limit: float) -> None:
    """Print the plain search's expansions with each shared holder counted once, and with the earlier bound."""
    table = Table(
        "task",
        "relevant parts/fits",
        "before: status",
        "expansions",
        "time",
        "holders once: status",
        "expansions",
        "time",
        "expansions after/before",
        title=f"The search's bound where holders are shared (plain search, limit {limit:g} s)",
    )
    tasks = [
        (f"synthetic {size} (seed {seed})", with_probabilities(synthetic_task(size, seed), seed + size))
        for size in (12, 20, 24, 28, 40)
    ]
    tasks += [("80-part tree, 15 uncertain fits (seed 2)", uncertain_tree(80, 15, 2))]
    tasks += [("4 components of 5", independent_components(4).task)]
    for name, task in tasks:
        row = [name, "{} / {}".format(*relevant_parts(task))]
        expansions = []
        for once in (False, True):
            compiled = compile_mdp(task, relevant_fits(task))
            compiled.holders_counted_once = once
            solution, seconds = timed(
                lambda compiled=compiled: search_compiled_mdp(compiled, limit, tie_breaking_step_cost(compiled))  # type: ignore[misc]
            )
            expansions.append(solution.states)
            row += [solution.optimality.value, f"{solution.states:,}", f"{seconds:.2f} s"]
        row.append(f"{expansions[1] / max(1, expansions[0]):.3f}")
        table.add_row(*row)
    console.print(table)


if __name__ == "__main__":
    main()
