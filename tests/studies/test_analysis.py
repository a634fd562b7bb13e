"""The study analysis: a synthetic export with a known effect, the paper's scenarios, the command."""

from __future__ import annotations

import csv
import json
import random
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.inputs import load_mapping, load_model
from causalplan.objects.catalog import Catalog, load_catalog
from causalplan.studies.analysis import analyse
from causalplan.studies.misconceptions import misconceptions
from causalplan.studies.statistics import wilson
from causalplan.studies.trials import ExportError, read_study, trial_rows
from causalplan.transfer.verdict import transfer_verdict
from tests.conftest import ROOT

PAPER = ROOT / "examples" / "paper"
USER_CATALOG = ROOT / "examples" / "catalog"

# Trained on two electric objects (near) or on one of each category (far); tested on an electric
# object (the user catalog's bedside lamp) and a combustion one.
CONDITIONS = {
    "near": (["desk_lamp", "flashlight"], {"bedside_lamp": 0.85, "candle": 0.25}),
    "far": (["desk_lamp", "candle"], {"bedside_lamp": 0.75, "kerosene_lamp": 0.75}),
}


@pytest.fixture(scope="module")
def catalog() -> Catalog:
    return load_catalog([USER_CATALOG])


def synthetic_export(per_condition: int, seed: int) -> dict[str, Any]:
    """Return an export whose shares of transfers are exactly the known rates of CONDITIONS.

    The transfers of each condition and test object are dealt to its participants at random
    (seeded), so the same shares come with different participants under another seed.
    """
    chance = random.Random(seed)
    trials = []
    for condition, (training, rates) in CONDITIONS.items():
        dealt = {}
        for test, rate in rates.items():
            successes = round(rate * per_condition)
            dealt[test] = chance.sample([True] * successes + [False] * (per_condition - successes), per_condition)
        for number in range(per_condition):
            participant = f"{condition}-{number}"
            for position, test in enumerate(rates, start=1):
                transfers = dealt[test][number]
                trials.append(
                    {
                        "trial_id": f"{participant}-{test}",
                        "participant_id": participant,
                        "condition": condition,
                        "training_order": training,
                        "test_object": test,
                        "position": position,
                        "verdict": "transfers" if transfers else "fails",
                        "decided_by": "planner" if transfers else "precheck",
                        "reasons": [] if transfers else [{"code": "missing_function"}],
                    }
                )
    return {"experiment": {"name": "synthetic"}, "participants": [], "trials": trials}


@pytest.mark.slow
def test_a_known_effect_is_found_in_the_right_direction_and_covered_by_the_intervals(catalog: Catalog) -> None:
    analysis = analyse(read_study(synthetic_export(80, seed=7), catalog), catalog)
    near = next(c for c in analysis.comparisons if c.name.startswith("near: same-category"))
    assert near.first_share.rate is not None and near.second_share.rate is not None
    assert near.first_share.rate > near.second_share.rate
    assert near.p_holm is not None and near.p_holm < 0.05
    assert near.odds_ratio > 1
    for cell in analysis.rates:
        true_rate = CONDITIONS[cell.condition][1][cell.test_object]
        assert cell.share.low is not None and cell.share.high is not None
        assert cell.share.low <= true_rate <= cell.share.high, cell
    far_on_candle_like = next(c for c in analysis.comparisons if c.name == "far: bedside_lamp vs kerosene_lamp")
    assert far_on_candle_like.p_holm is not None and far_on_candle_like.p_holm > 0.05
    effect = next(e for e in analysis.clustered.effects if e.name == "other_category_test")
    assert effect.odds_ratio < 1 and effect.interval[1] < 1
    assert any("the prediction holds" in conclusion for conclusion in analysis.conclusions)


def test_the_wilson_interval_matches_the_textbook_value() -> None:
    share = wilson(9, 10)
    assert share.low == pytest.approx(0.5958, abs=1e-4)
    assert share.high == pytest.approx(0.9821, abs=1e-4)
    assert wilson(0, 0).low is None


def test_the_papers_misconception_is_found_in_the_failed_model_only(catalog: Catalog) -> None:
    failed = json.loads(json.dumps(load_model(PAPER / "failed_desk_lamp.yaml", catalog).model.as_dict()))  # type: ignore[union-attr]
    good = load_model(PAPER / "desk_lamp.yaml", catalog).model.as_dict()  # type: ignore[union-attr]
    found = misconceptions(failed, catalog)
    assert [(item.function, item.parts) for item in found] == [("diffuse light", ("shade",))]
    assert misconceptions(good, catalog) == []


def _paper_trial(model: str, mapping: str, participant: str, catalog: Catalog) -> dict[str, Any]:
    loaded_model, loaded_mapping = load_model(PAPER / model, catalog), load_mapping(PAPER / mapping, catalog)
    verdict = transfer_verdict(loaded_model, loaded_mapping, catalog, simulate=False).as_dict()
    assert loaded_model.model is not None
    return {
        "trial_id": f"{participant}-1",
        "participant_id": participant,
        "condition": "near",
        "training_order": ["desk_lamp"],
        "test_object": "flashlight",
        "position": 1,
        "verdict": verdict["verdict"],
        "decided_by": verdict["decided_by"],
        "reasons": verdict["reasons"],
        "model": loaded_model.model.as_dict(),
    }


@pytest.mark.slow
def test_the_command_analyses_the_papers_two_participants(tmp_path: Path, catalog: Catalog) -> None:
    export = {
        "trials": [
            _paper_trial("desk_lamp.yaml", "flashlight_mapping.yaml", "success", catalog),
            _paper_trial("failed_desk_lamp.yaml", "failed_flashlight_mapping.yaml", "failure", catalog),
        ]
    }
    path = tmp_path / "export.json"
    path.write_text(json.dumps(export), encoding="utf-8")
    result = CliRunner().invoke(app, ["analyze", str(path), "--out", str(tmp_path / "out"), "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    assert data["rates"][0]["transfers"] == 1 and data["rates"][0]["trials"] == 2
    assert data["failure_reasons"]["near"] == {"missing_function": 1, "unmodelled_function": 1}
    assert list(data["misconceptions"]) == ["failure"]
    with (tmp_path / "out" / "trials.csv").open(encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert [row["transferred"] for row in rows] == ["1", "0"]
    assert rows[1]["misconception"] == "diffuse light"
    with (tmp_path / "out" / "codebook.csv").open(encoding="utf-8") as handle:
        documented = [row["column"] for row in csv.DictReader(handle)]
    assert documented == list(rows[0])
    assert (tmp_path / "out" / "rates.png").read_bytes().startswith(b"\x89PNG")
    assert b"<svg" in (tmp_path / "out" / "rates.svg").read_bytes()


def test_an_export_with_a_bad_trial_names_it(catalog: Catalog, tmp_path: Path) -> None:
    export = synthetic_export(1, seed=0)
    export["trials"][2]["verdict"] = "maybe"
    with pytest.raises(ExportError, match=r"trials\[2\]\.verdict is 'maybe'"):
        trial_rows(export, catalog)
    path = tmp_path / "broken.json"
    path.write_text("{not json", encoding="utf-8")
    result = CliRunner().invoke(app, ["analyze", str(path)])
    assert result.exit_code == 2
    assert "invalid_export" in result.output


def test_excluded_participants_are_counted_but_not_analysed(catalog: Catalog) -> None:
    export = synthetic_export(5, seed=1)
    export["participants"] = [{"participant_id": "near-0", "excluded": True, "exclusion_reason": "comprehension"}]
    analysis = analyse(read_study(export, catalog), catalog)
    assert analysis.as_dict()["excluded_participants"] == ["near-0"]
    assert all(row.participant_id != "near-0" for row in analysis.analysed)
