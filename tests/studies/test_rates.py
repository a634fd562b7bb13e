"""The one rates table: what it counts, what it leaves out and says so, and its chart."""

from __future__ import annotations

from typing import Any

from causalplan.objects.catalog import Catalog
from causalplan.studies.rates import rate_table, rates_chart
from causalplan.studies.trials import read_study

DESIGN = {
    "conditions": [
        {"name": "near", "training": ["desk_lamp"], "tests": ["flashlight", "candle"]},
        {"name": "far", "training": ["candle"], "tests": ["flashlight"]},
    ]
}


def trial(participant: str, condition: str, test: str, verdict: str) -> dict[str, Any]:
    training = next(entry["training"] for entry in DESIGN["conditions"] if entry["name"] == condition)
    return {
        "trial_id": f"{participant}-{test}",
        "participant_id": participant,
        "condition": condition,
        "training_order": training,
        "test_object": test,
        "verdict": verdict,
        "reasons": [],
    }


def export(**fields: Any) -> dict[str, Any]:
    trials = [
        trial("a", "near", "flashlight", "transfers"),
        trial("b", "near", "flashlight", "fails"),
        trial("c", "near", "flashlight", "invalid"),
        trial("d", "near", "flashlight", "undecided"),
        trial("e", "near", "flashlight", "transfers"),  # excluded: too fast
        trial("e", "near", "candle", "undecided"),  # excluded too: exclusion comes before undecided
    ]
    participants = [
        {"participant_id": "e", "excluded": True, "exclusion_reason": "too_fast"},
        {"participant_id": "f", "excluded": True, "exclusion_reason": "comprehension"},  # never reached step 3
    ]
    return {"experiment": {"design": DESIGN}, "participants": participants, "trials": trials, **fields}


def test_a_rate_counts_the_analysed_trials_and_the_ones_left_out_apart(catalog: Catalog) -> None:
    table = rate_table(read_study(export(), catalog), catalog)
    near_flashlight, near_candle, far_flashlight = (rate.as_dict() for rate in table.rates)
    assert {k: near_flashlight[k] for k in ("trials", "transfers", "fails", "undecided", "excluded")} == {
        "trials": 3,  # a, b and c: an invalid model counts as not transferred
        "transfers": 1,
        "fails": 2,
        "undecided": 1,
        "excluded": 1,
    }
    assert near_flashlight["generalization"] == "near" and near_flashlight["training_span"] == "one category"
    assert near_flashlight["interval"][0] < 1 / 3 < near_flashlight["interval"][1]
    assert (near_candle["trials"], near_candle["excluded"], near_candle["rate"]) == (0, 1, None)
    # The design's cell without any trial is a row too, in the design's order.
    assert (far_flashlight["condition"], far_flashlight["test_object"], far_flashlight["trials"]) == (
        "far",
        "flashlight",
        0,
    )
    assert far_flashlight["generalization"] == "far"


def test_what_is_left_out_is_said_with_its_reasons(catalog: Catalog) -> None:
    left_out = rate_table(read_study(export(), catalog), catalog).left_out
    assert (left_out.trials, left_out.analysed_trials, left_out.excluded_trials, left_out.undecided_trials) == (
        6,
        3,
        2,
        1,
    )
    assert left_out.reasons() == {"comprehension": 1, "too_fast": 1}
    assert left_out.says() == (
        "3 of 6 trials analysed; left out: 2 trials of 2 participants excluded by screening (comprehension 1, "
        "too_fast 1); 1 undecided trial (the planner could not decide in time)."
    )
    plain = export(participants=[], trials=[trial("a", "near", "flashlight", "transfers")])
    assert rate_table(read_study(plain, catalog), catalog).left_out.says() == "1 of 1 trial analysed; none left out."


def test_without_a_design_the_trials_name_the_rows(catalog: Catalog) -> None:
    data = export()
    del data["experiment"]
    rates = rate_table(read_study(data, catalog), catalog).rates
    assert [(rate.condition, rate.test_object) for rate in rates] == [("near", "candle"), ("near", "flashlight")]


def test_the_chart_shows_every_row_and_its_counts(catalog: Catalog) -> None:
    svg = rates_chart(rate_table(read_study(export(), catalog), catalog)).decode()
    assert "<!-- 1/3 -->" in svg and "<!-- candle -->" in svg and "none left out" not in svg
    assert rates_chart(rate_table(read_study(export(), catalog), catalog), "png").startswith(b"\x89PNG")
