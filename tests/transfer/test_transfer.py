"""Step 3 acceptance: the paper's two worked examples, and near/far examples both ways."""

from __future__ import annotations

import pytest

from causalplan.causal.diagnostics import Severity
from causalplan.objects.catalog import Catalog
from causalplan.transfer.verdict import TransferVerdict, Verdict, evaluate_transfer, generalization, needed_functions
from tests.conftest import example_mapping, example_model


def _verdict(model: str, mapping: str, catalog: Catalog) -> TransferVerdict:
    return evaluate_transfer(example_model(model, catalog), example_mapping(mapping, catalog), catalog)


def test_the_papers_successful_desk_lamp_model_transfers_to_the_flashlight(catalog: Catalog) -> None:
    verdict = _verdict("paper/desk_lamp.yaml", "paper/flashlight_mapping.yaml", catalog)
    assert verdict.verdict is Verdict.TRANSFERS
    assert verdict.generalization == "near"
    assert verdict.reasons == ()
    assert verdict.plan is not None
    assert [step.text for step in verdict.plan.steps] == [
        "Insert the batteries into the case.",
        "Screw the head onto the case.",
    ]


def test_the_papers_failed_model_fails_for_the_papers_two_reasons(catalog: Catalog) -> None:
    verdict = _verdict("paper/failed_desk_lamp.yaml", "paper/failed_flashlight_mapping.yaml", catalog)
    assert verdict.verdict is Verdict.FAILS
    found = {(reason.code, reason.labels) for reason in verdict.reasons}
    assert ("missing_function", ("turn electricity into light",)) in found
    assert ("unmodelled_function", ("hold things together",)) in found
    missing = next(reason for reason in verdict.reasons if reason.code == "missing_function")
    assert missing.severity is Severity.ERROR
    assert verdict.decided_by == "precheck"  # decided without running the planner


@pytest.mark.parametrize(
    ("model", "mapping", "verdict", "kind", "codes"),
    [
        ("near/candle.yaml", "near/kerosene_lamp_mapping.yaml", Verdict.TRANSFERS, "near", []),
        ("far/abstract_desk_lamp.yaml", "far/candle_mapping.yaml", Verdict.TRANSFERS, "far", []),
        (
            "paper/desk_lamp.yaml",
            "far/candle_mapping_for_paper_desk_lamp.yaml",
            Verdict.FAILS,
            "far",
            ["violates_true_mechanism"],
        ),
        ("near/candle.yaml", "far/flashlight_mapping_for_candle.yaml", Verdict.FAILS, "far", ["missing_function"]),
    ],
)
def test_near_and_far_examples(
    model: str, mapping: str, verdict: Verdict, kind: str, codes: list[str], catalog: Catalog
) -> None:
    result = _verdict(model, mapping, catalog)
    assert result.verdict is verdict
    assert result.generalization == kind
    assert [reason.code for reason in result.reasons] == codes


def test_no_assembly_sequence_when_the_parts_cannot_all_be_joined(user_catalog: Catalog) -> None:
    verdict = _verdict("paper/desk_lamp.yaml", "user/bedside_lamp_mapping.yaml", user_catalog)
    assert verdict.verdict is Verdict.FAILS
    assert [reason.code for reason in verdict.reasons] == ["no_assembly_sequence"]


def test_violating_the_true_mechanism_names_what_is_missing(catalog: Catalog) -> None:
    verdict = _verdict("paper/desk_lamp.yaml", "far/candle_mapping_for_paper_desk_lamp.yaml", catalog)
    reason = verdict.reasons[0]
    assert reason.labels == ("the wick has been lit",)
    assert verdict.plan is not None and verdict.plan.valid_under_model
    assert not verdict.plan.valid_under_true_mechanism


def test_a_missing_function_is_only_a_warning_when_another_rule_still_works(catalog: Catalog) -> None:
    from causalplan.causal.documents import SourceMap
    from causalplan.causal.model import read_labelling, read_model

    model, _ = read_model(
        {
            "object": "desk_lamp",
            "functions": {"base_with_cables": ["mains"], "light_bulb": ["glow"]},
            "rules": ["mains AND glow CAUSES light", "battery AND glow CAUSES light", "mains CAUSES battery"],
        },
        SourceMap(),
    )
    mapping, _ = read_labelling(
        {"object": "flashlight", "functions": {"batteries": ["battery"], "head": ["glow"]}}, SourceMap()
    )
    assert model is not None and mapping is not None
    verdict = evaluate_transfer(model, mapping, catalog)
    assert verdict.verdict is Verdict.TRANSFERS
    assert [(r.code, r.severity) for r in verdict.reasons] == [("missing_function", Severity.WARNING)]


def test_generalization_kinds(catalog: Catalog) -> None:
    lamp, torch, candle = catalog.get("desk_lamp"), catalog.get("flashlight"), catalog.get("candle")
    assert generalization(lamp, torch) == "near"
    assert generalization(lamp, candle) == "far"
    assert generalization(lamp, lamp) == "same_object"


def test_needed_functions_are_the_causes_no_rule_produces(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    assert set(needed_functions(model)) == {"provide electricity", "close the circuit", "turn electricity into light"}


def test_verdict_json_has_the_documented_keys(catalog: Catalog) -> None:
    data = _verdict("paper/desk_lamp.yaml", "paper/flashlight_mapping.yaml", catalog).as_dict()
    assert data["verdict"] == "transfers"
    assert data["generalization"] == "near"
    assert isinstance(data["plan"], list)
    assert {"action", "args", "text"} <= set(data["plan"][0])
    assert data["reasons"] == []
