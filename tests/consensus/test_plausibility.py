"""Mapping plausibility: a function given to a part, against what parts of that kind do in the catalog."""

from __future__ import annotations

import pytest

from causalplan.consensus.plausibility import THRESHOLD, MappingPlausibility, part_functions
from causalplan.objects.catalog import load_catalog
from causalplan.settings import Settings

IMPLAUSIBLE = [
    ("candle", "match", "close the circuit"),
    ("candle", "wick", "turn electricity into light"),
    ("candle", "wax", "provide electricity"),
    ("kerosene_lamp", "fuel_tank", "provide electricity"),
]
PLAUSIBLE = [
    ("candle", "match", "light the wick"),
    ("candle", "match", "start the fire"),
    ("candle", "wick", "make light"),
    ("flashlight", "batteries", "provide electricity"),
    ("flashlight", "batteries", "supply power"),
    ("flashlight", "head", "turn electricity into light"),
    ("flashlight", "head", "close the circuit"),
    ("flashlight", "head", "make light"),
]


@pytest.fixture(scope="module")
def scorer() -> MappingPlausibility:
    return MappingPlausibility(load_catalog(Settings().catalog_folders))


@pytest.mark.parametrize(("test_object", "part", "label"), IMPLAUSIBLE)
def test_a_function_of_the_other_category_is_implausible(
    scorer: MappingPlausibility, test_object: str, part: str, label: str
) -> None:
    found = scorer.pair(test_object, part, label)
    assert found.score < THRESHOLD, found


@pytest.mark.parametrize(("test_object", "part", "label"), PLAUSIBLE)
def test_a_function_of_the_objects_own_category_is_plausible(
    scorer: MappingPlausibility, test_object: str, part: str, label: str
) -> None:
    found = scorer.pair(test_object, part, label)
    assert found.score >= THRESHOLD, found


def test_a_mapping_is_as_plausible_as_its_least_plausible_function(scorer: MappingPlausibility) -> None:
    electric = {"object": "candle", "functions": {"wick": ["light the wick"], "match": ["close the circuit"]}}
    own = {"object": "candle", "functions": {"wick": ["draw up the molten wax"], "match": ["light the wick"]}}
    assert scorer("candle", electric) == scorer.pair("candle", "match", "close the circuit").score < THRESHOLD
    assert scorer("candle", own) >= THRESHOLD
    assert scorer("candle", {"object": "candle", "functions": {}}) == 1.0  # nothing given: nothing implausible


def test_a_parts_functions_are_those_of_the_fits_it_takes_part_in() -> None:
    candle = load_catalog(Settings().catalog_folders).get("candle")
    assert part_functions(candle) == {
        "wax": {"draw up the molten wax"},
        "wick": {"draw up the molten wax", "light the wick"},
        "match": {"light the wick"},
    }
