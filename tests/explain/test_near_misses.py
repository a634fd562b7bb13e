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


def _far_trial(participant: str, model: dict[str, Any], catalog: Catalog) -> dict[str, Any]:
    """A trial of the far design: trained on the desk lamp and the candle, tested on the flashlight."""
    return {
        "trial_id": f"{participant}-1",
        "participant_id": participant,
        "condition": "far",
        "training_order": ["desk_lamp", "candle"],
        "test_object": "flashlight",
        "position": 1,
        "verdict": "fails",
        "model": model,
        "mapping": yaml.safe_load((PAPER / "failed_flashlight_mapping.yaml").read_text(encoding="utf-8")),
    }


FAR_MODEL = {
    "goal": "light",
    "functions": {
        "desk_lamp": {"base_with_cables": ["provide electricity"], "light_bulb": ["turn electricity into light"]},
        "candle": {"wax": ["provide electricity"], "wick": ["turn electricity into light"]},
    },
    "rules": ["provide electricity AND turn electricity into light CAUSES light"],
}


def test_a_model_trained_on_two_objects_is_checked_on_its_test_object(catalog: Catalog) -> None:
    merged = {
        "object": "desk_lamp_and_candle",
        "goal": "light",
        "functions": {
            f"{object_id}.{part}": labels
            for object_id, parts in FAR_MODEL["functions"].items()
            for part, labels in parts.items()
        },
        "rules": FAR_MODEL["rules"],
    }
    export = {"trials": [_far_trial("stored", FAR_MODEL, catalog), _far_trial("merged", merged, catalog)]}
    [counts] = near_misses(export, catalog, simulate=False)
    # both shapes read to the same model, tried as step 3 tried it: two edits from working on the flashlight
    assert (counts.condition, counts.failed, counts.not_checked, counts.one_edit, counts.two_edits) == (
        "far",
        2,
        0,
        0,
        2,
    )
    assert counts.edits["give 'turn electricity into light' to the head"] == 2


def test_a_condition_whose_trials_cannot_be_checked_says_why_not_0_of_0(catalog: Catalog) -> None:
    no_mapping = _far_trial("no-mapping", FAR_MODEL, catalog)
    del no_mapping["mapping"]
    unknown = _far_trial("unknown", {**FAR_MODEL, "functions": {"desk_lamb": {"base": ["x"]}}}, catalog)
    [counts] = near_misses({"trials": [no_mapping, unknown]}, catalog, simulate=False)
    summary = counts.summary()
    assert "0 of 0" not in summary
    assert summary.startswith("far: none of its 2 failed transfer(s) could be checked: ")
    assert "the export has no mapping for the trial (1)" in summary and "not in the catalog" in summary
    assert counts.as_dict()["not_checked_because"] == dict(counts.not_checked_because)


def test_analyze_says_when_there_is_no_failed_transfer(tmp_path: Path, catalog: Catalog) -> None:
    export = _export(catalog)
    export["trials"] = export["trials"][:1]  # the one that transfers
    path = tmp_path / "export.json"
    path.write_text(json.dumps(export), encoding="utf-8")
    runner = CliRunner(env={"COLUMNS": "200"})
    result = runner.invoke(app, ["analyze", str(path), "--out", str(tmp_path / "out"), "--near-misses"])
    assert result.exit_code == 0, result.output
    assert "Near misses: there is no failed transfer to check" in result.stdout
