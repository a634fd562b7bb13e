"""The public Python API: the README's example, and its errors."""

from __future__ import annotations

from pathlib import Path

import pytest

import causalplan

PAPER = Path(__file__).resolve().parent.parent / "examples" / "paper"


def test_the_readme_example_plans_and_transfers_the_desk_lamp() -> None:
    model = causalplan.load_model(PAPER / "desk_lamp.yaml")
    result = causalplan.plan(model)
    assert [step.text for step in result.steps] == ["Screw the light bulb into the base with cables."]
    assert result.valid_under_true_mechanism
    assert result.validated_by == {"replay": "valid", "val": "valid"}
    mapping = causalplan.load_mapping(PAPER / "flashlight_mapping.yaml")
    verdict = causalplan.transfer_verdict(model, mapping)
    assert verdict.verdict.value == "transfers"
    assert verdict.generalization == "near"


def test_the_failed_model_fails_for_the_papers_two_reasons() -> None:
    model = causalplan.load_model(PAPER / "failed_desk_lamp.yaml")
    mapping = causalplan.load_mapping(PAPER / "failed_flashlight_mapping.yaml")
    verdict = causalplan.transfer_verdict(model, mapping, simulate=False)
    assert verdict.verdict.value == "fails"
    assert {reason.code for reason in verdict.reasons} >= {"missing_function", "unmodelled_function"}


def test_an_invalid_model_raises_with_its_report(tmp_path: Path) -> None:
    broken = tmp_path / "broken.yaml"
    broken.write_text("object: desk_lamp\nfunctions:\n  light_bulb: [glow]\nrules:\n  - glow CAUSES\n")
    with pytest.raises(causalplan.InvalidInputError) as raised:
        causalplan.load_model(broken)
    assert raised.value.report.errors
    assert str(broken) in raised.value.message


def test_the_catalog_lists_the_papers_objects() -> None:
    assert {"desk_lamp", "flashlight", "candle", "kerosene_lamp"} <= set(causalplan.catalog().objects)


def test_simulate_checks_the_plan_in_physics() -> None:
    report = causalplan.simulate(causalplan.load_model(PAPER / "desk_lamp.yaml"))
    assert report.produces_goal
