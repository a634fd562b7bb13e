"""The exact solver: against brute force over every policy, and against the classical ratio rule."""

from __future__ import annotations

import pytest

from causalplan.objects.catalog import Catalog
from causalplan.troubleshoot.episode import run_episode
from causalplan.troubleshoot.errors import TooLargeError
from causalplan.troubleshoot.priors import Suspicion, oracle_suspicion, uniform_suspicion
from causalplan.troubleshoot.solver import solve
from causalplan.troubleshoot.structure import Structure, structure_of
from causalplan.troubleshoot.synthetic import chain, star
from tests.troubleshoot.exhaustive import best_expected_actions


def _longest_episode(structure: Structure, suspicion: Suspicion) -> int:
    policy = solve(structure, suspicion)
    return max(run_episode(policy, part).actions for part in structure.parts)


@pytest.mark.parametrize("object_id", ["desk_lamp", "flashlight", "candle"])
@pytest.mark.parametrize("strategy", ["uniform", "oracle"])
def test_the_solver_matches_brute_force_over_all_policies_on_small_catalog_objects(
    catalog: Catalog, object_id: str, strategy: str
) -> None:
    obj = catalog.get(object_id)
    structure = structure_of(obj)
    suspicion = uniform_suspicion(obj) if strategy == "uniform" else oracle_suspicion(obj)
    horizon = _longest_episode(structure, suspicion) + 2
    brute = best_expected_actions(structure, suspicion, horizon)
    assert solve(structure, suspicion).expected_actions() == pytest.approx(brute, abs=1e-9)


@pytest.mark.parametrize(
    ("structure", "weights"),
    [
        (chain(3, visible=True), (0.0, 0.2, 0.3, 0.5)),  # the likeliest part is the hardest to reach
        (chain(3, visible=False), (0.1, 0.2, 0.3, 0.4)),
        (star(3, visible=False), (0.0, 0.25, 0.25, 0.5)),
        (star(3, visible=True), (0.1, 0.3, 0.2, 0.4)),
    ],
    ids=["chain-visible", "chain-hidden", "star-hidden", "star-visible"],
)
def test_the_solver_matches_brute_force_on_synthetic_objects(structure: Structure, weights: tuple[float, ...]) -> None:
    suspicion = Suspicion("test", weights)
    horizon = _longest_episode(structure, suspicion) + 2
    brute = best_expected_actions(structure, suspicion, horizon)
    assert solve(structure, suspicion).expected_actions() == pytest.approx(brute, abs=1e-9)


def test_a_shorter_horizon_than_the_policy_needs_cannot_reach_its_value(catalog: Catalog) -> None:
    # The brute force is a real search: cut short, it finds no policy that always repairs.
    obj = catalog.get("desk_lamp")
    structure = structure_of(obj)
    suspicion = oracle_suspicion(obj)
    policy = solve(structure, suspicion)
    horizon = max(run_episode(policy, fault.part).actions for fault in obj.faults)
    assert best_expected_actions(structure, suspicion, horizon - 1) > solve(structure, suspicion).expected_actions()


def _ratio_rule_cost(probabilities: list[float], per_part: float, last_is_free: bool) -> float:
    """Return the expected cost of checking parts by decreasing probability over (equal) cost."""
    ordered = sorted(probabilities, reverse=True)
    cost = 0.0
    for position, probability in enumerate(ordered, start=1):
        checks = min(position, len(ordered) - 1) if last_is_free else position
        cost += probability * checks * per_part
    return cost


@pytest.mark.parametrize("probabilities", [[0.5, 0.3, 0.2], [0.2, 0.5, 0.3], [0.6, 0.25, 0.1, 0.05]])
def test_with_equal_access_and_only_repairs_the_solver_follows_the_ratio_rule(probabilities: list[float]) -> None:
    # Each try is detach, replace, attach, test: 4 actions, the same for every part (Kadane and Simon).
    structure = star(len(probabilities), visible=False)
    policy = solve(structure, Suspicion("test", (0.0, *probabilities)))
    assert policy.expected_actions() == pytest.approx(_ratio_rule_cost(probabilities, 4.0, last_is_free=False))
    order = [step.part for step in run_episode(policy, "base").steps if step.kind == "replace"]
    by_probability = sorted(structure.parts[1:], key=lambda part: -probabilities[structure.index(part) - 1])
    assert order[: len(probabilities)] == by_probability


@pytest.mark.parametrize("probabilities", [[0.5, 0.3, 0.2], [0.1, 0.2, 0.3, 0.4], [0.25] * 4])
def test_with_equal_access_and_visible_faults_the_solver_inspects_by_the_ratio_rule(probabilities: list[float]) -> None:
    # Inspections cost 1 each, by decreasing probability; the last suspect needs none; then 4 to repair.
    structure = star(len(probabilities), visible=True)
    policy = solve(structure, Suspicion("test", (0.0, *probabilities)))
    expected = _ratio_rule_cost(probabilities, 1.0, last_is_free=True) + 4.0
    assert policy.expected_actions() == pytest.approx(expected)


def test_one_test_after_several_replacements_beats_the_ratio_rule_when_the_tail_is_heavy() -> None:
    # Where the ratio rule stops being optimal: with eight equally likely hidden faults, replacing two
    # parts before one test saves a test for every fault further down the order (18 -> 17.25).
    probabilities = [1 / 8] * 8
    policy = solve(star(8, visible=False), Suspicion("test", (0.0, *probabilities)))
    assert policy.expected_actions() == pytest.approx(17.25)
    assert _ratio_rule_cost(probabilities, 4.0, last_is_free=False) == pytest.approx(18.0)
    steps = [step.kind for step in run_episode(policy, "p2").steps]
    assert steps.count("replace") == 2 and steps.count("test") == 1


def test_a_part_without_weight_is_suspected_once_every_weighted_part_is_cleared() -> None:
    structure = star(3, visible=True)
    policy = solve(structure, Suspicion("test", (0.0, 0.0, 0.5, 0.5)))
    episode = run_episode(policy, "p1")
    checked = [step.part for step in episode.steps if step.kind in ("inspect", "replace")]
    assert checked.index("p1") > max(checked.index("p2"), checked.index("p3"))
    assert episode.steps[-1].observed == "goal"


def test_the_solver_refuses_rather_than_approximates_beyond_its_limit() -> None:
    with pytest.raises(TooLargeError) as raised:
        solve(star(5, visible=False), Suspicion("test", (1.0,) * 6), max_states=1000)
    assert raised.value.code == "troubleshooting_too_large"
