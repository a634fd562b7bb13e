"""The heuristic MDP search (improved LAO*): the exact solver's optimum, over fewer states; anytime bounds."""

from __future__ import annotations

import dataclasses

import pytest

from causalplan.comparison.families import independent_components, with_probabilities
from causalplan.comparison.synthetic import synthetic_task
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners.mdp import Optimality, solve_mdp, solve_mdp_search
from causalplan.planners.mdp.bounds import bound, cheapest_test_cost
from causalplan.planners.mdp.model import STEP_COST, compile_mdp, relevant_fits
from causalplan.planners.mdp.objective import solve_for
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanStatus
from tests.conftest import example_mapping, example_model
from tests.planners.test_pipeline import PAPER_PLANS


def _value(success: float, attempts: float) -> float:
    return 2 * success - 1 - STEP_COST * attempts


def _assert_same_optimum(task: PlanningTask) -> None:
    exact, heuristic = solve_mdp(task, 60.0), solve_mdp_search(task, 60.0)
    assert exact.status is heuristic.status
    assert heuristic.optimality is Optimality.OPTIMAL
    if exact.status is PlanStatus.SOLVED:
        assert exact.success_probability is not None and exact.expected_actions is not None
        assert heuristic.success_probability is not None and heuristic.expected_actions is not None
        assert (
            abs(
                _value(exact.success_probability, exact.expected_actions)
                - _value(heuristic.success_probability, heuristic.expected_actions)
            )
            < 1e-9
        )
        assert abs(exact.success_probability - heuristic.success_probability) < 1e-9
        assert heuristic.actions == exact.actions  # the same rule breaks ties: the first fit wins


@pytest.mark.parametrize(("model_file", "mapping_file"), sorted(PAPER_PLANS, key=str))
@pytest.mark.parametrize("seed", [None, 0, 1])
def test_it_finds_the_exact_optimum_on_the_paper_objects(
    model_file: str, mapping_file: str | None, seed: int | None, catalog: Catalog
) -> None:
    model = example_model(model_file, catalog)
    mapping = example_mapping(mapping_file, catalog) if mapping_file else None
    task = build_task(model, catalog.get(mapping.object_id if mapping else model.object_id), mapping)
    _assert_same_optimum(task if seed is None else with_probabilities(task, seed, low=0.5))


@pytest.mark.parametrize("parts", [3, 4, 6, 8, 10, 12, 16])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_it_finds_the_exact_optimum_on_synthetic_tasks(parts: int, seed: int) -> None:
    _assert_same_optimum(with_probabilities(synthetic_task(parts, seed), seed))


@pytest.mark.slow
@pytest.mark.parametrize(("parts", "seed"), [(20, 0), (20, 1), (24, 0), (24, 1), (28, 0)])
def test_it_finds_the_exact_optimum_up_to_the_exact_solvers_limit(parts: int, seed: int) -> None:
    task = with_probabilities(synthetic_task(parts, seed), parts)
    _assert_same_optimum(task)
    assert solve_mdp_search(task, 60.0).states * 5 <= solve_mdp(task, 60.0).states


def test_it_expands_far_fewer_states_than_the_exact_solver_stores() -> None:
    task = with_probabilities(synthetic_task(16, 1), 1)
    assert solve_mdp_search(task).states * 10 <= solve_mdp(task).states


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_bound_at_the_start_is_never_below_the_optimum(seed: int) -> None:
    task = with_probabilities(synthetic_task(12, seed), seed)
    exact = solve_mdp(task)
    assert exact.success_probability is not None and exact.expected_actions is not None
    compiled = compile_mdp(task, relevant_fits(task))
    root = bound(compiled, compiled.base, 0, 0, STEP_COST)
    assert exact.success_probability - 1e-12 <= root.success < 1.0
    assert _value(exact.success_probability, exact.expected_actions) - 1e-12 <= root.value


def test_the_cheapest_test_order_respects_precedence() -> None:
    # Alone, the riskier test (0.5) goes first: 1 + 0.5 attempts. If it must come after the
    # sure one (1.0), both always run: 2 attempts.
    assert cheapest_test_cost({1: 1.0, 2: 0.5}, {}) == pytest.approx(1.5)
    assert cheapest_test_cost({1: 1.0, 2: 0.5}, {2: 1}) == pytest.approx(2.0)
    # a chain merges: 4 after 1 after nothing; 2 free. Riskiest group first.
    assert cheapest_test_cost({1: 0.9, 4: 0.1, 2: 0.5}, {4: 1}) == pytest.approx(
        min(1 + 0.9 * (1 + 0.1 * 1), 1 + 0.5 * (1 + 0.9 * 1))
    )


def test_at_the_time_limit_it_answers_with_bounds_not_a_hang() -> None:
    task = with_probabilities(synthetic_task(120, 0), 120)
    solution = solve_mdp_search(task, time_limit=1.0)
    assert solution.status is PlanStatus.SOLVED and solution.optimality is Optimality.BOUNDED
    assert solution.success_probability is not None and solution.success_upper is not None
    assert 0.0 <= solution.success_probability <= solution.success_upper <= 1.0
    assert solution.actions and "no policy does better" in solution.message


def test_an_unreachable_goal_is_unsolvable(catalog: Catalog) -> None:
    model = example_model("paper/failed_desk_lamp.yaml", catalog)
    mapping = example_mapping("paper/failed_flashlight_mapping.yaml", catalog)
    solution = solve_mdp_search(build_task(model, catalog.get(mapping.object_id), mapping))
    assert solution.status is PlanStatus.UNSOLVABLE and solution.success_probability == 0.0


@pytest.mark.parametrize(("parts", "seed"), [(8, 0), (12, 1), (16, 2)])
def test_as_planned_both_solvers_agree_with_the_tie_breaking_step_cost(parts: int, seed: int) -> None:
    task = with_probabilities(synthetic_task(parts, seed), seed)
    exact, heuristic = solve_for(task, 60.0, exact=True), solve_for(task, 60.0)
    assert exact.success_probability is not None and heuristic.success_probability is not None
    assert abs(exact.success_probability - heuristic.success_probability) < 1e-9
    assert exact.actions == heuristic.actions


def test_the_most_reliable_policy_is_not_traded_for_fewer_attempts_when_success_is_unlikely() -> None:
    # Every fit succeeds with 0.3, so success is unlikely: a fixed step cost of 0.001 an attempt
    # outweighs it, and the value's optimum rushes into a dead end; the tie-breaking cost does not.
    base = synthetic_task(16, 0)
    fits = tuple(dataclasses.replace(fit, probability=0.3) for fit in base.obj.fits)
    task = dataclasses.replace(base, obj=dataclasses.replace(base.obj, fits=fits))
    assert solve_mdp_search(task).status is solve_mdp(task).status is PlanStatus.UNSOLVABLE
    solution = solve_for(task, 60.0)
    assert solution.status is PlanStatus.SOLVED and solution.success_probability is not None
    assert solution.success_probability > 0.0
    assert solution.success_probability == pytest.approx(solve_for(task, 60.0, exact=True).success_probability)


def test_an_anytime_plan_says_so_in_its_json() -> None:
    # 142 relevant fits whose alternatives keep the splitting solver from finishing in seconds.
    task = with_probabilities(synthetic_task(320, 2), 322)
    data = plan_task(task, "mdp", 2.0).as_dict()
    assert data["status"] == "solved" and data["optimality"] == "bounded" and data["objective"] == "probability"
    low, high = data["success_probability_bounds"]  # type: ignore[misc]
    assert 0.0 <= low <= high <= 1.0 and data["bound_gap"] == pytest.approx(
        high - low, abs=2e-6
    )  # each rounded to 6 places
    assert data["expected_actions"] is None and "no policy does better" in str(data["message"])


def test_the_json_says_whether_the_attempts_are_proved_fewest() -> None:
    # The search closes on the small tree (fewest proved); the split solver proves only the reliability.
    closed = plan_task(with_probabilities(synthetic_task(12, 1), 12), "mdp", 30.0).as_dict()
    split = plan_task(with_probabilities(synthetic_task(120, 0), 120), "mdp", 30.0).as_dict()
    assert closed["optimality"] == split["optimality"] == "optimal"
    assert closed["fewest_attempts"] is True and split["fewest_attempts"] is False


def test_it_stops_optimal_as_soon_as_the_bounds_meet() -> None:
    # Four independent components: the policy's success meets the bound long before every state is solved.
    family = independent_components(4)
    solution = solve_mdp_search(family.task, 30.0)
    assert solution.optimality is Optimality.OPTIMAL and solution.message.startswith("Proved optimal after")
    assert solution.success_probability == pytest.approx(family.success_probability, rel=1e-9)
    assert solution.expected_actions is not None and not solution.fewest_attempts
    assert solution.states < 1000


def test_a_search_out_of_time_never_calls_a_solvable_task_unsolvable(catalog: Catalog) -> None:
    # A finished search's policy evaluated past the deadline, not cut at it: cut, its success
    # read 0.0 and the desk lamp came back "unsolvable" at the smallest time limit.
    task = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.objects["desk_lamp"])
    statuses = {plan_task(task, "mdp", 0.001).status for _ in range(40)}
    assert PlanStatus.UNSOLVABLE not in statuses
