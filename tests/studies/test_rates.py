"""The one rates table: what it counts, what it leaves out and says so, and its chart."""

from __future__ import annotations

from typing import Any

from matplotlib.transforms import Bbox

from causalplan.objects.catalog import Catalog
from causalplan.studies.rates import rate_table, rates_chart, rates_figure
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


def crowded_export() -> dict[str, Any]:
    """Four conditions on two test objects, twelve trials each: low rates on one object, full on the other."""
    names = ("c1", "c2", "c3", "c4")
    design = {"conditions": [{"name": n, "training": ["desk_lamp"], "tests": ["flashlight", "candle"]} for n in names]}
    trials = [
        {
            "trial_id": f"{name}-{test}-{number}",
            "participant_id": f"{name}-{number}",
            "condition": name,
            "training_order": ["desk_lamp"],
            "test_object": test,
            "verdict": "transfers" if test == "candle" or number == 0 else "fails",
            "reasons": [],
        }
        for name in names
        for test in ("flashlight", "candle")
        for number in range(12)
    ]
    return {"experiment": {"design": design}, "participants": [], "trials": trials}


def test_the_charts_legend_and_counts_cover_no_interval_and_no_other_count(catalog: Catalog) -> None:
    figure = rates_figure(rate_table(read_study(crowded_export(), catalog), catalog))
    renderer = figure.canvas.get_renderer()  # type: ignore[attr-defined]
    axes = figure.axes[0]
    drawn = axes.get_legend()
    assert drawn is not None
    legend = drawn.get_window_extent(renderer)
    pixels = figure.dpi / 72
    intervals = [  # each point and each cap, one marker at a time (a line's own box spans all of its points)
        Bbox.from_extents(x - half, y - half, x + half, y + half)
        for line in axes.get_lines()
        for half in [line.get_markersize() * pixels / 2]
        for x, y in axes.transData.transform(line.get_xydata())
    ]
    intervals += [  # the bars: each segment of the errorbars' line collections, in pixels
        Bbox(axes.transData.transform(segment))
        for bars in axes.collections
        for segment in bars.get_segments()  # type: ignore[attr-defined]
    ]
    counts = [text.get_window_extent(renderer) for text in axes.texts]
    assert sorted(text.get_text() for text in axes.texts) == ["1/12"] * 4 + ["12/12"] * 4
    assert not any(legend.overlaps(interval) for interval in intervals)
    assert not any(a.overlaps(b) for i, a in enumerate(counts) for b in counts[i + 1 :])
    assert not any(count.overlaps(interval) for count in counts for interval in intervals)
