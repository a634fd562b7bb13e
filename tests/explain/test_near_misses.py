"""Near misses counted per condition: failed transfers one or two edits from working, and which edits."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import yaml
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.explain.near_misses import near_misses
from causalplan.objects.catalog import Catalog
from tests.conftest import EXAMPLES
from tests.studies.test_analysis import _paper_trial

PAPER = EXAMPLES / "paper"


def _trial(model: str, mapping: str, participant: str, catalog: Catalog) -> dict[str, Any]:
    trial = _paper_trial(model, mapping, participant, catalog)
    trial["mapping"] = yaml.safe_load((PAPER / mapping).read_text(encoding="utf-8"))
    return trial


def _export(catalog: Catalog) -> dict[str, Any]:
    return {
        "trials": [
            _trial("desk_lamp.yaml", "flashlight_mapping.yaml", "success", catalog),
            _trial("failed_desk_lamp.yaml", "failed_flashlight_mapping.yaml", "failure", catalog),
            _trial("failed_desk_lamp.yaml", "failed_flashlight_mapping.yaml", "gone", catalog),
        ],
        "participants": [{"participant_id": "gone", "excluded": True}],
    }


def test_the_papers_failed_trial_is_one_edit_from_working(catalog: Catalog) -> None:
    [counts] = near_misses(_export(catalog), catalog)
    assert (counts.condition, counts.failed, counts.one_edit, counts.two_edits) == ("near", 1, 1, 0)
    assert counts.edits == {"give 'turn electricity into light' to the batteries": 1}
    assert counts.summary().startswith("near: 1 of 1 failed transfers are fixed by one edit, 0 more by two")


def test_an_unreadable_trial_is_counted_not_guessed(catalog: Catalog) -> None:
    export = _export(catalog)
    export["trials"][1]["mapping"] = {"object": "no_such_object", "functions": {}}
    [counts] = near_misses(export, catalog)
    assert (counts.failed, counts.not_checked, counts.one_edit) == (1, 1, 0)


def test_analyze_reports_near_misses(tmp_path: Path, catalog: Catalog) -> None:
    path = tmp_path / "export.json"
    path.write_text(json.dumps(_export(catalog)), encoding="utf-8")
    result = CliRunner().invoke(app, ["analyze", str(path), "--out", str(tmp_path / "out"), "--near-misses", "--json"])
    assert result.exit_code == 0, result.output
    [counts] = json.loads(result.stdout)["near_misses"]
    assert (counts["failed"], counts["one_edit"]) == (1, 1)
