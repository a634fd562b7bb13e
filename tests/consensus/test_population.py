"""Synthetic participants: reproducible, and each error kind does what it says."""

from __future__ import annotations

import pytest

from causalplan.consensus.population import ERROR_KINDS, UnknownScenarioError, population

NONE = dict.fromkeys(ERROR_KINDS, 0.0)


def test_the_same_seed_gives_the_same_participants() -> None:
    assert population("desk_lamp", 5, seed=3) == population("desk_lamp", 5, seed=3)
    assert population("desk_lamp", 5, seed=3) != population("desk_lamp", 5, seed=4)


def test_without_errors_every_participant_holds_the_general_model() -> None:
    lines = population("desk_lamp", 3, seed=1, rates=NONE, tests=("flashlight",))
    assert [line["errors"] for line in lines] == [[], [], []]
    assert lines[0]["model"] == {
        "object": "desk_lamp",
        "goal": "light",
        "functions": {
            "base_with_cables": ["provide energy"],
            "light_bulb": ["start the process", "turn energy into light"],
        },
        "rules": [
            "provide energy AND start the process CAUSES energy is released",
            "energy is released AND turn energy into light CAUSES light",
        ],
    }
    assert lines[0]["mapping"] == {
        "object": "flashlight",
        "functions": {"batteries": ["provide energy"], "head": ["start the process", "turn energy into light"]},
    }


def test_effect_as_cause_makes_diffuse_light_necessary() -> None:
    (line,) = population("desk_lamp", 1, seed=1, rates=NONE | {"effect_as_cause": 1.0}, tests=("flashlight",))
    assert line["errors"] == ["effect_as_cause"]
    model = line["model"]
    assert isinstance(model, dict)
    assert model["rules"][-1] == "energy is released AND turn energy into light AND diffuse light CAUSES light"


def test_object_specific_words_are_not_mapped_on_the_other_category() -> None:
    near, far = population(
        "desk_lamp", 1, seed=1, rates=NONE | {"object_specific": 1.0}, tests=("flashlight", "candle")
    )
    assert near["mapping"] == {
        "object": "flashlight",
        "functions": {
            "batteries": ["provide electricity"],
            "head": ["close the circuit", "turn electricity into light"],
        },
    }
    assert far["mapping"] == {"object": "candle", "functions": {}}


def test_an_uncaused_intermediate_drops_the_rule_that_causes_it() -> None:
    (line,) = population("candle", 1, seed=1, rates=NONE | {"uncaused_intermediate": 1.0}, tests=("kerosene_lamp",))
    model = line["model"]
    assert isinstance(model, dict)
    assert model["rules"] == ["energy is released AND start the process CAUSES light"]


def test_a_missed_part_leaves_one_part_without_functions() -> None:
    (line,) = population("desk_lamp", 1, seed=1, rates=NONE | {"missed_part": 1.0}, tests=("flashlight",))
    mapping = line["mapping"]
    assert isinstance(mapping, dict)
    assert len(mapping["functions"]) == 1


def test_an_object_without_a_scenario_names_the_ones_there_are() -> None:
    with pytest.raises(UnknownScenarioError, match="candle, desk_lamp"):
        population("toy_car", 1, seed=0)
    with pytest.raises(UnknownScenarioError, match="no mapping for toy_car"):
        population("desk_lamp", 1, seed=0, tests=("toy_car",))
