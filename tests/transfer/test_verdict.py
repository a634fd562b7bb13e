"""Transfer verdicts use the simulator: replay is the fast pre-check, physics has the last word."""

from __future__ import annotations

import pytest

from causalplan.causal.documents import parse_text
from causalplan.causal.model import Labelling
from causalplan.inputs import mapping_from_data
from causalplan.objects.catalog import Catalog
from causalplan.transfer.verdict import Verdict, evaluate_transfer
from tests.conftest import example_mapping, example_model
from tests.sim.fixtures import CAPPED_LAMP, CAPPED_LAMP_MAPPING, parsed_object


def test_a_transfer_carries_the_simulation_summary(catalog: Catalog) -> None:
    verdict = evaluate_transfer(
        example_model("paper/desk_lamp.yaml", catalog),
        example_mapping("paper/flashlight_mapping.yaml", catalog),
        catalog,
    )
    assert verdict.verdict is Verdict.TRANSFERS and verdict.decided_by == "planner"
    assert verdict.simulation is not None and verdict.simulation.passed
    summary = verdict.as_dict()["simulation"]
    assert summary == verdict.simulation.summary()
    assert summary["produces_goal"] is True


def test_without_simulation_the_verdict_has_none(catalog: Catalog) -> None:
    verdict = evaluate_transfer(
        example_model("near/candle.yaml", catalog),
        example_mapping("near/kerosene_lamp_mapping.yaml", catalog),
        catalog,
        simulate=False,
    )
    assert verdict.verdict is Verdict.TRANSFERS
    assert verdict.simulation is None and verdict.as_dict()["simulation"] is None


def test_a_failure_found_by_replay_is_not_simulated(catalog: Catalog) -> None:
    verdict = evaluate_transfer(
        example_model("paper/desk_lamp.yaml", catalog),
        example_mapping("far/candle_mapping_for_paper_desk_lamp.yaml", catalog),
        catalog,
    )
    assert [reason.code for reason in verdict.reasons] == ["violates_true_mechanism"]
    assert verdict.decided_by == "planner" and verdict.simulation is None


@pytest.fixture(scope="module")
def capped_catalog(catalog: Catalog) -> Catalog:
    capped = parsed_object(CAPPED_LAMP)
    return Catalog({**catalog.objects, capped.id: capped})


def capped_mapping(catalog: Catalog) -> Labelling:
    data, source, _ = parse_text(CAPPED_LAMP_MAPPING, "capped_lamp_mapping.yaml")
    loaded = mapping_from_data(data, source, catalog)
    assert loaded.is_valid and loaded.mapping is not None
    return loaded.mapping


def test_physics_overturns_a_plan_that_works_on_paper(capped_catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", capped_catalog)
    verdict = evaluate_transfer(model, capped_mapping(capped_catalog), capped_catalog)
    assert verdict.plan is not None and verdict.plan.valid_under_true_mechanism  # replay: it works
    assert verdict.verdict is Verdict.FAILS and verdict.decided_by == "simulator"
    (reason,) = verdict.reasons
    assert reason.code == "violates_true_mechanism"
    assert reason.labels == ("the bulb is screwed into the socket",)
    assert "in simulation the real capped lamp does not produce light" in reason.message
    assert "stopped against the lamp body" in reason.message
    assert verdict.as_dict()["simulation"]["failure"] == "misaligned"
