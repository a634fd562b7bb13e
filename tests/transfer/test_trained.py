"""An exported trial's model read back on each training object, from all three shapes an export holds."""

from __future__ import annotations

from typing import Any

from causalplan.objects.catalog import Catalog
from causalplan.objects.reference import reference_model
from causalplan.transfer.trained import read_trained_model

RULES = [
    "provide energy AND start the process CAUSES energy is released",
    "energy is released AND turn energy into light CAUSES light",
]
LAMP = {"base_with_cables": ["provide energy", "start the process"], "light_bulb": ["turn energy into light"]}
CANDLE = {"wax": ["provide energy"], "wick": ["turn energy into light"], "match": ["start the process"]}


def stored(functions: dict[str, Any]) -> dict[str, Any]:
    """The research page's export: the participant's model as stored (object -> part -> labels)."""
    return {"goal": "light", "functions": functions, "rules": RULES}


def merged() -> dict[str, Any]:
    """`synthetic-study`'s export: one document, parts written object.part."""
    functions = {f"desk_lamp.{part}": labels for part, labels in LAMP.items()}
    functions |= {f"candle.{part}": labels for part, labels in CANDLE.items()}
    return {"object": "desk_lamp_and_candle", "goal": "light", "functions": functions, "rules": RULES}


def test_the_far_designs_model_reads_the_same_from_both_of_its_shapes(catalog: Catalog) -> None:
    training = ["desk_lamp", "candle"]
    for document in (stored({"desk_lamp": LAMP, "candle": CANDLE}), merged()):
        trained = read_trained_model(document, training, catalog)
        assert trained.problem is None
        assert list(trained.on_objects) == training
        lamp, candle = trained.on_objects["desk_lamp"], trained.on_objects["candle"]
        assert lamp.object_id == "desk_lamp" and set(lamp.labelling.functions) == set(LAMP)
        assert candle.object_id == "candle" and set(candle.labelling.functions) == set(CANDLE)
        assert trained.tried is lamp  # step 3 tries the model on the first training object, as the service does
        assert [rule.text for rule in lamp.rules] == RULES


def test_a_model_file_is_one_training_object(catalog: Catalog) -> None:
    document = {"object": "desk_lamp", "goal": "light", "functions": LAMP, "rules": RULES}
    for training in ([], ["desk_lamp"]):
        trained = read_trained_model(document, training, catalog)
        assert trained.problem is None and list(trained.on_objects) == ["desk_lamp"]
    one_stored = read_trained_model(stored({"desk_lamp": LAMP}), ["desk_lamp"], catalog)
    assert one_stored.tried is not None and one_stored.tried.object_id == "desk_lamp"


def test_what_cannot_be_read_is_said_in_words(catalog: Catalog) -> None:
    assert read_trained_model(None, ["desk_lamp"], catalog).problem == "the trial has no model"
    unknown = read_trained_model(stored({"desk_lamb": LAMP}), ["desk_lamb"], catalog)
    assert unknown.problem is not None and "not in the catalog" in unknown.problem and unknown.tried is None
    wrong_part = merged()
    wrong_part["functions"]["lamp.shade"] = ["diffuse light"]
    problem = read_trained_model(wrong_part, ["desk_lamp", "candle"], catalog).problem
    assert problem == "its model's part 'lamp.shade' is not written 'object.part' with one of desk_lamp, candle"
    uncaused = stored({"desk_lamp": LAMP, "candle": CANDLE}) | {"rules": ["current AND start the process CAUSES light"]}
    invalid = read_trained_model(uncaused, ["desk_lamp", "candle"], catalog).problem
    assert invalid is not None and invalid.startswith("its model is invalid: ")


def test_a_model_without_a_goal_is_tried_with_its_objects_goal_as_it_was_checked(catalog: Catalog) -> None:
    document = dict(reference_model(catalog.get("toy_car")))
    del document["goal"]
    trained = read_trained_model(document, ["toy_car"], catalog)
    assert trained.problem is None and trained.tried is not None and trained.tried.goal == "motion"
