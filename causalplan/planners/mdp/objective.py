"""What the MDP optimises: the highest success probability, or the fewest expected attempts.

``probability`` (the default, as the paper) maximises the value ``2 P - 1 - cost E[attempts]``
with a step cost scaled to the task (``search.tie_breaking_step_cost``) so that it only breaks
ties: the most reliable policy, to a relative precision of ``STEP_COST / 2``, then the fewest
attempts.

``attempts`` asks for the fewest expected attempts among policies that succeed with at least
a required probability. It is solved by Lagrangian relaxation: a larger step cost trades
success for attempts, and a bisection on the (log) step cost finds the largest cost whose
optimal policy still meets the requirement. Each step of it is an optimal solve, so the answer
is the best policy on that trade-off curve; a randomised policy or one off the curve could in
principle use fewer attempts (constrained MDPs can need randomisation), which is not searched.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable

from causalplan.errors import CausalPlanError
from causalplan.pddl.task import PlanningTask
from causalplan.planners.mdp.composed import solve_by_components
from causalplan.planners.mdp.exact import solve_compiled_mdp
from causalplan.planners.mdp.model import CompiledMdp, MdpSolution, Objective, Optimality, compile_mdp, relevant_fits
from causalplan.planners.mdp.search import search_compiled_mdp, tie_breaking_step_cost
from causalplan.planners.result import PlanStatus

Solver = Callable[[CompiledMdp, float, float], MdpSolution]
"""An MDP solver: the compiled MDP, the time limit and the step cost in; the solution out."""

MAX_STEP_COST = 4.0
"""Beyond this, one attempt costs more than twice a success is worth: attempts dominate."""
BISECTIONS = 12


class ObjectiveError(CausalPlanError):
    """An objective that is not known, or a required success probability out of range."""

    code = "invalid_objective"


def check_objective(objective: str, required_success: float | None) -> Objective:
    """Return the objective named, or raise ObjectiveError saying what is wrong."""
    try:
        chosen = Objective(objective)
    except ValueError:
        choices = ", ".join(item.value for item in Objective)
        raise ObjectiveError(
            f"Unknown objective '{objective}'; choose one of: {choices}.", details={"objective": objective}
        ) from None
    if chosen is Objective.ATTEMPTS:
        if required_success is None:
            raise ObjectiveError(
                "The 'attempts' objective needs a required success probability (e.g. --required-success 0.9).",
                details={"objective": objective},
            )
        if not 0.0 < required_success <= 1.0 or math.isnan(required_success):
            raise ObjectiveError(
                f"The required success probability must be in (0, 1], not {required_success}.",
                details={"required_success": required_success},
            )
    return chosen


def _meets(solution: MdpSolution, required: float) -> bool:
    return (
        solution.status is PlanStatus.SOLVED
        and solution.optimality is Optimality.OPTIMAL
        and solution.success_probability is not None
        and solution.success_probability >= required - 1e-12
    )


def solve_for(
    task: PlanningTask,
    time_limit: float,
    objective: Objective = Objective.PROBABILITY,
    required_success: float | None = None,
    exact: bool = False,
) -> MdpSolution:
    """Solve the task's MDP for ``objective`` with the heuristic search (or the exact solver).

    The MDP is compiled once: every solve of the bisection shares it (and its goal cache).
    """
    solve: Solver = solve_compiled_mdp if exact else search_compiled_mdp
    # The most reliable policy (and, for ``attempts``, whether ``required_success`` is reachable
    # at all) by the independent components and splitting (composed.py); the bisection's steps
    # weigh attempts against success, which only the plain search and the exact solver optimise.
    most_reliable: Solver = solve_compiled_mdp if exact else solve_by_components
    deadline = time.monotonic() + time_limit
    compiled = compile_mdp(task, relevant_fits(task))
    step_cost = tie_breaking_step_cost(compiled)
    reliable = most_reliable(compiled, max(0.0, deadline - time.monotonic()), step_cost)
    if objective is Objective.PROBABILITY:
        return reliable
    assert required_success is not None
    tagged = dataclasses.replace(reliable, objective=Objective.ATTEMPTS, required_success=required_success)
    if reliable.status is not PlanStatus.SOLVED:
        return tagged
    if not _meets(reliable, required_success):
        reachable = reliable.success_probability or 0.0
        return dataclasses.replace(
            tagged,
            status=PlanStatus.UNSOLVABLE,
            actions=(),
            policy=(),
            message=f"No policy succeeds with probability {required_success:g}: the most reliable one reaches "
            f"{reachable:.6f}"
            + (" (a lower bound: the limit came first)." if reliable.optimality is Optimality.BOUNDED else "."),
        )
    best = reliable
    low, high = math.log(step_cost), math.log(MAX_STEP_COST)
    for _ in range(BISECTIONS):
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            break
        cost = math.exp((low + high) / 2)
        candidate = solve(compiled, remaining, cost)
        if _meets(candidate, required_success):
            low = math.log(cost)
            if (candidate.expected_actions or math.inf) < (best.expected_actions or math.inf) - 1e-12:
                best = candidate
        else:
            high = math.log(cost)
    return dataclasses.replace(best, objective=Objective.ATTEMPTS, required_success=required_success)
