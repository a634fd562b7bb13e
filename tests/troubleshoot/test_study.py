"""Troubleshooting as a study's dependent measure: per condition and test object, models against baselines."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.objects.catalog import Catalog
from causalplan.troubleshoot.study import troubleshooting_by_object
from tests.conftest import EXAMPLES

PAPER = EXAMPLES / "paper"


def _trial(model: str, mapping: str, participant: str) -> dict[str, Any]:
    return {
        "trial_id": f"{participant}-1",
        "participant_id": participant,
        "condition": "near",
        "training_order": ["desk_lamp"],
        "test_object": "flashlight",
        "position": 1,
        "verdict": "transfers",
        "decided_by": "planner",
        "reasons": [],
        "model": yaml.safe_load((PAPER / model).read_text(encoding="utf-8")),
        "mapping": yaml.safe_load((PAPER / mapping).read_text(encoding="utf-8")),
    }


def _export() -> dict[str, Any]:
    return {
        "trials": [
            _trial("desk_lamp.yaml", "flashlight_mapping.yaml", "success"),
            _trial("failed_desk_lamp.yaml", "failed_flashlight_mapping.yaml", "failure"),
            _trial("desk_lamp.yaml", "flashlight_mapping.yaml", "gone"),
        ],
        "participants": [{"participant_id": "gone", "excluded": True}],
    }


def test_each_model_is_scored_against_no_model_and_the_catalog_priors(catalog: Catalog) -> None:
    [row] = troubleshooting_by_object(_export(), catalog)
    assert (row.condition, row.test_object) == ("near", "flashlight")
    # The failed mapping gives no route to light on the flashlight: not scored, never guessed.
    assert (len(row.model_actions), row.not_scored) == (1, 1)
    assert row.oracle is not None and row.uniform is not None
    assert row.oracle <= row.model_actions[0] < row.uniform
    assert row.better_than_uniform == 1
    assert "1 of 1 do better than no model (1 not scored)" in row.summary()


def test_analyze_reports_troubleshooting(tmp_path: Path) -> None:
    path = tmp_path / "export.json"
    path.write_text(json.dumps(_export()), encoding="utf-8")
    args = ["analyze", str(path), "--out", str(tmp_path / "out"), "--troubleshooting", "--json"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    [row] = json.loads(result.stdout)["troubleshooting"]
    assert (row["scored"], row["not_scored"]) == (1, 1)
    assert row["model_mean_expected_actions"] == pytest.approx(6.9)
    assert row["uniform_expected_actions"] == pytest.approx(6.95)


def test_a_study_s_model_with_functions_per_training_object_is_read_by_its_rules(catalog: Catalog) -> None:
    export = _export()
    lamp = export["trials"][0]["model"]
    export["trials"][0]["model"] = {
        "goal": "light",
        "functions": {"desk_lamp": lamp["functions"]},
        "rules": lamp["rules"],
    }
    [row] = troubleshooting_by_object(export, catalog)
    assert len(row.model_actions) == 1
    export["trials"][0]["model"] = {"goal": "light", "functions": {}, "rules": ["light CAUSES"]}
    [row] = troubleshooting_by_object(export, catalog)
    assert (len(row.model_actions), row.not_scored) == (0, 2)
