"""The new objects' examples: each model checks; one transfer works, others fail for reasons the paper names."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.objects.catalog import load_catalog
from causalplan.service.api.schemas.experiments import ExperimentIn
from causalplan.studies.far_generalization import template_conditions
from tests.conftest import EXAMPLES

OBJECTS = EXAMPLES / "objects"
WITH_COVER = OBJECTS / "headlamp_with_cover.yaml"
runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "200"})


@pytest.mark.parametrize("object_id", ["headlamp", "solar_lantern", "oil_lamp", "gas_lantern"])
def test_each_new_object_has_a_model_that_checks_and_plans(object_id: str) -> None:
    model = OBJECTS / f"{object_id}.yaml"
    assert runner.invoke(app, ["check", str(model)]).exit_code == 0
    planned = runner.invoke(app, ["plan", str(model), "--json"])
    assert planned.exit_code == 0, planned.output


@pytest.mark.parametrize(
    ("model", "mapping", "verdict", "reasons"),
    [
        (OBJECTS / "headlamp.yaml", "flashlight_mapping_for_headlamp.yaml", "transfers", []),
        (
            OBJECTS / "headlamp_with_cover.yaml",
            "solar_lantern_mapping_for_headlamp.yaml",
            "fails",
            ["missing_function"],
        ),
        (OBJECTS / "gas_lantern.yaml", "oil_lamp_mapping_for_gas_lantern.yaml", "fails", ["missing_function"]),
        (
            EXAMPLES / "paper" / "desk_lamp.yaml",
            "headlamp_mapping_for_desk_lamp.yaml",
            "fails",
            ["violates_true_mechanism"],
        ),
    ],
)
def test_the_example_transfers_have_the_verdicts_their_comments_give(
    model: Path, mapping: str, verdict: str, reasons: list[str]
) -> None:
    result = runner.invoke(app, ["transfer", str(model), str(OBJECTS / mapping), "--json"])
    data = json.loads(result.output)
    assert data["verdict"] == verdict
    assert [reason["code"] for reason in data["reasons"]] == reasons


def test_the_papers_design_as_an_experiment_file_is_the_template_and_a_valid_body() -> None:
    body = json.loads((EXAMPLES / "studies" / "far_generalization.json").read_text(encoding="utf-8"))
    assert body["conditions"] == template_conditions("far_generalization", load_catalog())
    assert ExperimentIn.model_validate(body).template == "far_generalization"
