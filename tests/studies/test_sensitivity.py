"""The sensitivity analysis: rates without the transfers that rest on implausible mappings."""

from __future__ import annotations

from typing import Any

from causalplan.consensus.plausibility import MappingPlausibility
from causalplan.objects.catalog import load_catalog
from causalplan.settings import Settings
from causalplan.studies.analysis import analyse_export

FAR = {"name": "far", "training": ["desk_lamp"], "tests": ["candle"]}


def trial(number: int, verdict: str, functions: dict[str, list[str]]) -> dict[str, Any]:
    return {
        "trial_id": f"trial-{number}",
        "participant_id": f"person-{number}",
        "condition": "far",
        "training_order": ["desk_lamp"],
        "test_object": "candle",
        "position": 1,
        "verdict": verdict,
        "reasons": [] if verdict == "transfers" else [{"code": "missing_function"}],
        "mapping": {"object": "candle", "functions": functions},
    }


def export() -> dict[str, Any]:
    own = {"wick": ["light the wick"], "match": ["light the wick"]}
    electric = {"wick": ["turn electricity into light"], "match": ["close the circuit"]}
    return {
        "experiment": {"id": "e", "design": {"conditions": [FAR]}},
        "participants": [],
        "trials": [trial(1, "transfers", own), trial(2, "transfers", electric), trial(3, "fails", electric)],
    }


def test_the_rates_are_given_again_without_transfers_on_implausible_mappings() -> None:
    catalog = load_catalog(Settings().catalog_folders)
    analysis = analyse_export(export(), catalog, MappingPlausibility(catalog))
    assert [(rate.transfers, rate.trials) for rate in analysis.rates] == [(2, 3)]
    found = analysis.sensitivity
    assert found is not None and found.scored_transfers == 2
    assert [item.trial_id for item in found.implausible] == ["trial-2"]  # a fail is not a transfer to doubt
    assert [(rate.transfers, rate.trials) for rate in found.without.rates] == [(1, 2)]
    reported = analysis.as_dict()["mapping_plausibility"]
    assert reported["implausible_transfers"][0]["mapping"]["functions"]["match"] == ["close the circuit"]
    assert "1 of 2 analysed transfers rest on an implausible mapping" in reported["says"]


def test_without_a_scorer_there_is_no_sensitivity_analysis() -> None:
    catalog = load_catalog(Settings().catalog_folders)
    analysis = analyse_export(export(), catalog)
    assert analysis.sensitivity is None and analysis.as_dict()["mapping_plausibility"] is None
