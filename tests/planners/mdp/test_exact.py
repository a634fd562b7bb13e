"""The exact MDP planner, checked against truth: fd-opt's lengths, Monte-Carlo, risk, limits."""

from __future__ import annotations

import dataclasses
import random
import time
from pathlib import Path

import pytest

from causalplan.comparison.families import with_probabilities
from causalplan.comparison.synthetic import synthetic_task
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners import fd
from causalplan.planners.mdp import MAX_RELEVANT_FITS, MdpSolution, relevant_fits, solve_mdp
from causalplan.planners.pipeline import plan_task
from causalplan.planners.replay import replay
from causalplan.planners.result import PlanStatus
from tests.conftest import example_mapping, example_model
from tests.planners.test_pipeline import PAPER_PLANS


def _certain(task: PlanningTask) -> PlanningTask:
    fits = tuple(dataclasses.replace(fit, probability=1.0) for fit in task.obj.fits)
    return dataclasses.replace(task, obj=dataclasses.replace(task.obj, fits=fits))


def _paper_task(model_file: str, mapping_file: str | None, catalog: Catalog) -> PlanningTask:
    model = example_model(model_file, catalog)
    mapping = example_mapping(mapping_file, catalog) if mapping_file else None
    return build_task(model, catalog.get(mapping.object_id if mapping else model.object_id), mapping)


@pytest.mark.parametrize(("model_file", "mapping_file"), sorted(PAPER_PLANS, key=str))
def test_with_certain_fits_its_plans_are_as_short_as_fd_opt_on_paper_tasks(
    model_file: str, mapping_file: str | None, catalog: Catalog
) -> None:
    task = _paper_task(model_file, mapping_file, catalog)
    mdp, optimal = plan_task(task, "mdp"), plan_task(task, "fd-opt")
    assert mdp.status is PlanStatus.SOLVED and mdp.valid_under_true_mechanism
    assert len(mdp.steps) == len(optimal.steps)
    assert mdp.success_probability == 1.0


@pytest.mark.parametrize("parts", range(2, 13))
@pytest.mark.parametrize("seed", [0, 1])
def test_with_certain_fits_its_plans_are_as_short_as_fd_opt_on_synthetic_tasks(parts: int, seed: int) -> None:
    task = _certain(synthetic_task(parts, seed))
    mdp, optimal = plan_task(task, "mdp"), plan_task(task, "fd-opt")
    assert mdp.status is optimal.status is PlanStatus.SOLVED
    assert len(mdp.steps) == len(optimal.steps)


def _monte_carlo(task: PlanningTask, solution: MdpSolution, rollouts: int, seed: int) -> float:
    """Run the solution's own policy with random outcomes; return the fraction reaching the goal."""
    policy = {(frozenset(e["made"]), frozenset(e["failed"])): str(e["attempt"]) for e in solution.policy}  # type: ignore[arg-type]
    fits = {fit.id: fit for fit in task.obj.fits}
    rng = random.Random(seed)
    successes = 0
    for _ in range(rollouts):
        made: list[str] = []
        failed: set[str] = set()
        while (attempt := policy.get((frozenset(made), frozenset(failed)))) is not None:
            if rng.random() < fits[attempt].probability:
                made.append(attempt)
            else:
                failed.add(attempt)
        actions = tuple((fits[f].primitive, (fits[f].moving_part, fits[f].fixed_part, f)) for f in made)
        successes += replay(task, actions).valid_under_model  # an independent judge of the goal
    return successes / rollouts


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_reported_success_probability_matches_monte_carlo(seed: int) -> None:
    task = with_probabilities(synthetic_task(9, seed), seed, low=0.6)
    solution = solve_mdp(task)
    assert solution.status is PlanStatus.SOLVED and solution.success_probability is not None
    assert 0.0 < solution.success_probability < 1.0
    assert len(solution.policy) < 200  # the whole reachable policy, so the rollouts never leave it
    assert abs(_monte_carlo(task, solution, 10_000, seed) - solution.success_probability) < 0.02


def test_it_picks_the_reliable_route_where_fd_takes_the_risky_one(user_catalog: Catalog) -> None:
    task = build_task(example_model("user/worn_lamp.yaml", user_catalog), user_catalog.get("worn_lamp"))
    fd, mdp = plan_task(task, "fd"), plan_task(task, "mdp")
    assert [step.fit for step in fd.steps] == ["bulb_into_worn_socket"]
    assert fd.success_probability == 0.5
    assert [step.fit for step in mdp.steps] == ["adapter_into_spare_socket", "bulb_into_adapter"]
    # 0.99 * 0.99, plus: the adapter fails (0.01), then the worn socket still works half the time.
    assert mdp.success_probability == pytest.approx(0.99 * 0.99 + 0.01 * 0.5)
    assert mdp.expected_actions == pytest.approx(2.0)


def test_auto_uses_the_mdp_when_a_fit_in_play_may_fail(user_catalog: Catalog) -> None:
    task = build_task(example_model("user/worn_lamp.yaml", user_catalog), user_catalog.get("worn_lamp"))
    result = plan_task(task, "auto")
    assert result.planner_used == "mdp"
    assert result.fallback_reason is not None and "bulb_into_worn_socket" in result.fallback_reason


def test_auto_uses_fd_when_every_fit_is_certain(catalog: Catalog) -> None:
    result = plan_task(_paper_task("paper/desk_lamp.yaml", None, catalog), "auto")
    assert result.planner_used == "fd" and result.fallback_reason is None


def test_auto_falls_back_to_the_mdp_when_fd_is_unavailable(catalog: Catalog, monkeypatch: pytest.MonkeyPatch) -> None:
    fd.use_search_binary(Path("/nonexistent/downward"))
    try:
        result = plan_task(_paper_task("paper/desk_lamp.yaml", None, catalog), "auto")
    finally:
        fd.use_search_binary(None)
    assert result.status is PlanStatus.SOLVED and result.planner_used == "mdp"
    assert result.fallback_reason is not None and "error" in result.fallback_reason


def test_only_fits_that_matter_are_searched(catalog: Catalog) -> None:
    task = _paper_task("paper/desk_lamp.yaml", None, catalog)  # the shade carries nothing used
    assert [fit.id for fit in relevant_fits(task)] == ["bulb_into_socket"]
    task = _paper_task("near/candle.yaml", "near/kerosene_lamp_mapping.yaml", catalog)
    # the burner carries no function but the wick goes in through it; the chimney is irrelevant
    assert {fit.id for fit in relevant_fits(task)} == {"burner_onto_tank", "wick_into_burner", "lighter_lights_wick"}


def test_an_unreachable_goal_is_unsolvable_not_a_hang(catalog: Catalog) -> None:
    task = _paper_task("paper/failed_desk_lamp.yaml", "paper/failed_flashlight_mapping.yaml", catalog)
    solution = solve_mdp(task)
    assert solution.status is PlanStatus.UNSOLVABLE and solution.success_probability == 0.0


def test_sixteen_relevant_parts_solve_exactly() -> None:
    task = with_probabilities(synthetic_task(20, 0), 0, low=0.7)
    parts = {p for fit in relevant_fits(task) for p in (fit.moving_part, fit.fixed_part)}
    assert len(parts) >= 16
    assert solve_mdp(task, time_limit=60).status is PlanStatus.SOLVED


def test_too_many_relevant_fits_is_declined_at_once() -> None:
    task = synthetic_task(200, 0)
    assert len(relevant_fits(task)) > MAX_RELEVANT_FITS
    started = time.monotonic()
    solution = solve_mdp(task)
    assert solution.status is PlanStatus.TOO_LARGE and "stops at" in solution.message
    assert time.monotonic() - started < 3.0  # far from the 10 s it would search for; loose for a busy machine


def test_a_state_space_beyond_the_budget_stops_at_the_time_limit_as_a_timeout() -> None:
    task = synthetic_task(32, 0)
    started = time.monotonic()
    solution = solve_mdp(task, time_limit=0.5)
    assert solution.status is PlanStatus.TIMEOUT and "did not finish within 0.5 s" in solution.message
    assert time.monotonic() - started < 5.0


def test_a_time_limit_that_passes_before_the_first_state_is_a_timeout_not_too_large(catalog: Catalog) -> None:
    task = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    for time_limit in (1e-6, 5e-324):
        assert solve_mdp(task, time_limit=time_limit).status is PlanStatus.TIMEOUT
