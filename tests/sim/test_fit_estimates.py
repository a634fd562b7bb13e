"""Fit probabilities from noisy robot insertions: tight fits lower than loose ones, zero noise certain, seeded."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import pytest

from causalplan.errors import CatalogError
from causalplan.objects.overlay import MIN_PROBABILITY, apply_overlay, overlay_data
from causalplan.sim.fit_estimates import FitEstimate, estimate_fit, estimate_fits, wilson_interval
from tests.conftest import builtin_catalog

PAPER_OBJECTS = ("desk_lamp", "flashlight", "candle", "kerosene_lamp")


@cache
def desk_lamp_estimates(seed: int = 0) -> dict[str, FitEstimate]:
    lamp = builtin_catalog().get("desk_lamp")
    return {estimate.fit: estimate for estimate in estimate_fits(lamp, trials=200, seed=seed)}


@pytest.mark.slow
def test_under_the_same_noise_the_tight_e27_thread_is_less_likely_than_the_shades_clip() -> None:
    estimates = desk_lamp_estimates()
    thread, clip = estimates["bulb_into_socket"], estimates["shade_onto_ring"]
    assert thread.probability < clip.probability
    assert thread.interval[1] < clip.interval[0]  # not a fluke of 200 trials: the intervals do not overlap
    assert thread.failures["misaligned"] > 0


@pytest.mark.slow
@pytest.mark.parametrize("object_id", PAPER_OBJECTS)
def test_without_noise_every_fit_of_the_paper_objects_always_works(object_id: str) -> None:
    for estimate in estimate_fits(builtin_catalog().get(object_id), trials=5, noise_mm=0.0, noise_deg=0.0):
        assert estimate.probability == 1.0, estimate
        assert estimate.failures == {}


@pytest.mark.slow
def test_the_same_seed_gives_the_same_numbers_and_another_seed_others() -> None:
    lamp = builtin_catalog().get("desk_lamp")
    fit = lamp.fit("bulb_into_socket")
    again = estimate_fit(lamp, fit, trials=200, seed=0)
    assert again == desk_lamp_estimates()["bulb_into_socket"]
    assert estimate_fit(lamp, fit, trials=200, seed=1) != again


def test_a_grasp_far_off_is_lost() -> None:
    lamp = builtin_catalog().get("desk_lamp")
    estimate = estimate_fit(lamp, lamp.fit("shade_onto_ring"), trials=50, noise_mm=10.0, noise_deg=0.0)
    assert estimate.failures.get("grasp_lost", 0) > 40


def test_the_wilson_interval_of_known_counts() -> None:
    low, high = wilson_interval(7, 10)
    assert (round(low, 4), round(high, 4)) == (0.3968, 0.8922)
    assert wilson_interval(0, 20)[0] == 0.0
    assert wilson_interval(20, 20)[1] == pytest.approx(1.0)


def test_the_json_form_of_an_estimate() -> None:
    data = FitEstimate("f", 10, 7, (0.39677, 0.89221), {"misaligned": 2, "grasp_lost": 1}).as_dict()
    assert data == {
        "id": "f",
        "trials": 10,
        "successes": 7,
        "probability": 0.7,
        "interval": [0.3968, 0.8922],
        "failures": {"misaligned": 2, "grasp_lost": 1},
    }


def test_an_overlay_gives_the_catalog_the_measured_probabilities(tmp_path: Path) -> None:
    import yaml

    rows = [estimate.as_dict() for estimate in desk_lamp_estimates().values()]
    path = tmp_path / "overlay.yaml"
    path.write_text(yaml.safe_dump(overlay_data({"desk_lamp": rows}, "test")), encoding="utf-8")
    overlaid = apply_overlay(builtin_catalog(), path).get("desk_lamp")
    assert overlaid.fit("bulb_into_socket").probability == desk_lamp_estimates()["bulb_into_socket"].probability
    assert builtin_catalog().get("desk_lamp").fit("bulb_into_socket").probability == 1.0  # the catalog is unchanged


def test_a_fit_that_never_worked_is_written_as_barely_possible() -> None:
    never = FitEstimate("bulb_into_socket", 5, 0, (0.0, 0.43), {"misaligned": 5}).as_dict()
    data = overlay_data({"desk_lamp": [never]}, "test")
    assert data["objects"] == {
        "desk_lamp": {"bulb_into_socket": {"probability": MIN_PROBABILITY, "interval": [0.0, 0.43], "trials": 5}}
    }


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("objects: {lamp_x: {}}", "no object 'lamp_x'"),
        ("objects: {desk_lamp: {bulb_in: {probability: 0.5}}}", "objects > desk_lamp > bulb_in: the desk lamp has no"),
        ("objects: {desk_lamp: {bulb_into_socket: {probability: 0}}}", "probability 0 is not in (0, 1]"),
        ("objects: {desk_lamp: {bulb_into_socket: {probability: high}}}", "needs 'probability', a number"),
        ("fits: []", "needs 'objects'"),
        ("objects: [", "is not YAML or JSON"),
        ("objects:\n  desk_lamp: {}\n  desk_lamp: {}\n", "names 'desk_lamp' twice (line 3)"),
    ],
)
def test_a_wrong_overlay_says_what_is_wrong_and_where(tmp_path: Path, text: str, says: str) -> None:
    path = tmp_path / "overlay.yaml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(CatalogError) as raised:
        apply_overlay(builtin_catalog(), path)
    assert says in raised.value.message
