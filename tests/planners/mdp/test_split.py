"""The solver that splits the rest after every attempt: mdp-exact's success probability, over far fewer residuals."""

from __future__ import annotations

import dataclasses
import random

import pytest

from causalplan.comparison.families import with_probabilities
from causalplan.comparison.synthetic import synthetic_task
from causalplan.pddl.task import PlanningTask
from causalplan.planners.mdp import solve_mdp
from causalplan.planners.mdp.model import compile_mdp, relevant_fits
from causalplan.planners.mdp.search import decide
from causalplan.planners.mdp.split_solve import solve_split
from causalplan.planners.result import PlanStatus


@pytest.mark.parametrize(
    ("parts", "seed"), [(8, 0), (12, 1), (16, 2), (20, 0), pytest.param(28, 0, marks=pytest.mark.slow)]
)
def test_it_finds_the_exact_solvers_success_probability(parts: int, seed: int) -> None:
    task = with_probabilities(synthetic_task(parts, seed), parts)
    exact = solve_mdp(task, 60.0, step_cost=1e-9)
    solution = solve_split(compile_mdp(task, relevant_fits(task)), 60.0)
    assert solution is not None and solution.status is exact.status is PlanStatus.SOLVED
    assert exact.success_probability is not None and solution.success_probability is not None
    assert abs(solution.success_probability - exact.success_probability) < 1e-9
    assert solution.states < exact.states


def test_its_policy_is_the_one_it_evaluated() -> None:
    # Walk every outcome of the policy ``decide`` follows and add the chances of reaching the goal.
    task = with_probabilities(synthetic_task(12, 1), 12)
    compiled = compile_mdp(task, relevant_fits(task))
    solution = solve_split(compiled, 60.0)
    assert solution is not None and solution.success_probability is not None

    def success(made: int, failed: int) -> float:
        if compiled.goal_holds(compiled.parts_of((made, failed))[0]):
            return 1.0
        index = decide(compiled, solution, (made, failed))
        if index < 0:
            return 0.0
        p, bit = compiled.probability[index], 1 << index
        return p * success(made | bit, failed) + (1 - p) * (success(made, failed | bit) if p < 1 else 0.0)

    assert success(0, 0) == pytest.approx(solution.success_probability, abs=1e-12)


def _with_chances(task: PlanningTask, seed: int, chances: tuple[float, ...]) -> PlanningTask:
    rng = random.Random(seed)
    fits = tuple(dataclasses.replace(fit, probability=rng.choice(chances)) for fit in task.obj.fits)
    return dataclasses.replace(task, obj=dataclasses.replace(task.obj, fits=fits))


@pytest.mark.parametrize(("parts", "seed"), [(12, 0), (16, 3), (20, 4), (24, 5), (22, 1)])
@pytest.mark.parametrize("chances", [(0.7, 0.8, 0.8, 1.0), (0.5, 0.9, 1.0)])
def test_forced_attempts_and_dropped_fits_keep_the_optimum(parts: int, seed: int, chances: tuple[float, ...]) -> None:
    # Equal chances on alternative sockets and certain fits: where the dominance rules apply most.
    task = _with_chances(synthetic_task(parts, seed), seed * 7 + parts, chances)
    exact = solve_mdp(task, 60.0, step_cost=1e-9)
    solution = solve_split(compile_mdp(task, relevant_fits(task)), 60.0)
    assert solution is not None and exact.success_probability is not None
    assert solution.success_probability == pytest.approx(exact.success_probability, abs=1e-9)


@pytest.mark.slow
def test_it_proves_a_tree_with_79_relevant_parts() -> None:
    # The benchmark's 200-part tree: alternative sockets tie it into one group at the start.
    task = with_probabilities(synthetic_task(200, 0), 200)
    compiled = compile_mdp(task, relevant_fits(task))
    solution = solve_split(compiled, 20.0)
    assert len(compiled.fits) == 96
    assert solution is not None and solution.status is PlanStatus.SOLVED and solution.success_probability is not None
    assert solution.success_upper == solution.success_probability
