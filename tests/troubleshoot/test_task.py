"""Troubleshooting the catalog's objects: the strategies' measures, episodes, and bad input."""

from __future__ import annotations

from dataclasses import replace

import pytest

from causalplan.objects.catalog import Catalog
from causalplan.troubleshoot.errors import FaultNotNeededError, NoFaultsError, UnknownFaultPartError
from causalplan.troubleshoot.measures import REPAIR_BONUS, reward_share
from causalplan.troubleshoot.structure import structure_of
from causalplan.troubleshoot.task import troubleshooting_task
from tests.conftest import example_mapping, example_model


def test_on_the_broken_desk_lamp_the_good_model_beats_uniform_and_the_failed_model(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    good = troubleshooting_task(lamp, example_model("paper/desk_lamp.yaml", catalog)).table()
    failed = troubleshooting_task(lamp, example_model("paper/failed_desk_lamp.yaml", catalog)).table()
    assert good["model"].expected_actions < good["uniform"].expected_actions
    assert failed["model"].expected_actions > good["model"].expected_actions
    assert good["oracle"].expected_actions <= good["model"].expected_actions
    assert good["model"].reward_share > failed["model"].reward_share


def test_the_oracle_is_never_above_any_strategy_on_any_catalog_object(catalog: Catalog) -> None:
    for obj in catalog.objects.values():
        table = troubleshooting_task(obj).table()
        assert table["oracle"].expected_actions <= table["uniform"].expected_actions + 1e-9, obj.id
        # Under its own prior, the oracle's expectation is the catalog's: the same number.
        assert table["oracle"].own_expected_actions == pytest.approx(table["oracle"].expected_actions), obj.id


def test_the_desk_lamp_model_helps_on_the_flashlight_and_misleads_on_the_candle(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    near = troubleshooting_task(
        catalog.get("flashlight"), model, example_mapping("paper/flashlight_mapping.yaml", catalog)
    ).table()
    assert near["oracle"].expected_actions <= near["model"].expected_actions < near["uniform"].expected_actions
    # Far: the mapping gives the match no function, so the model suspects it last (a damp match
    # is found only after the wax and the wick are cleared): worse than no model at all.
    far = troubleshooting_task(
        catalog.get("candle"), model, example_mapping("far/candle_mapping_for_paper_desk_lamp.yaml", catalog)
    ).table()
    assert far["model"].expected_actions > far["uniform"].expected_actions >= far["oracle"].expected_actions
    match = {fault.part: fault for fault in far["model"].faults}["match"]
    assert match.actions > {fault.part: fault for fault in far["uniform"].faults}["match"].actions


def test_every_episode_ends_with_the_broken_part_replaced_and_a_test_showing_the_goal(catalog: Catalog) -> None:
    for obj in catalog.objects.values():
        task = troubleshooting_task(obj)
        structure = structure_of(obj)
        for strategy in task.strategies:
            for fault in obj.faults:
                steps = task.episode(strategy, fault.part).steps
                assert (steps[-1].kind, steps[-1].observed) == ("test", "goal"), (obj.id, strategy, fault.part)
                last_test = max((i for i, step in enumerate(steps[:-1]) if step.kind == "test"), default=-1)
                replaced = {step.part for step in steps[last_test + 1 :] if step.kind == "replace"}
                assert fault.part in replaced, (obj.id, strategy, fault.part)
                attached = structure.body
                for step in steps:  # every move is allowed where it is made, and the test is on the whole object
                    assert step.part is None or step.part in obj.part_ids
                    if step.kind in ("detach", "attach"):
                        part = structure.index(step.part or "")
                        allowed = structure.can_detach if step.kind == "detach" else structure.can_attach
                        assert allowed(part, attached), (obj.id, step)
                        attached ^= 1 << part
                    if step.kind == "test":
                        assert structure.is_assembled(attached)


def test_the_measures_count_actions_under_the_catalog_priors(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    result = troubleshooting_task(lamp).table()["oracle"]
    by_part = {fault.part: fault for fault in result.faults}
    assert result.expected_actions == pytest.approx(
        0.7 * by_part["light_bulb"].actions + 0.3 * by_part["base_with_cables"].actions
    )
    assert result.worst_actions == max(fault.actions for fault in result.faults)
    assert all(fault.fewest_actions <= fault.actions for fault in result.faults)
    assert reward_share(7, 7) == 1.0 and reward_share(9, 7) == pytest.approx((REPAIR_BONUS - 9) / (REPAIR_BONUS - 7))


def test_bad_faults_and_objects_get_errors_with_codes(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    task = troubleshooting_task(lamp)
    with pytest.raises(UnknownFaultPartError, match="Did you mean 'light_bulb'") as unknown:
        task.episode("oracle", "light_bulp")
    assert unknown.value.code == "unknown_fault_part"
    with pytest.raises(FaultNotNeededError, match="still gives light") as shade:
        task.episode("oracle", "shade")
    assert shade.value.code == "fault_not_needed"
    with pytest.raises(NoFaultsError) as none:
        troubleshooting_task(replace(lamp, faults=(), fault_priors=None))
    assert none.value.code == "object_without_faults"
