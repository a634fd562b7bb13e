"""The paper's misconception found in models of one training object and of two (the far design), or why not."""

from __future__ import annotations

from typing import Any

from causalplan.objects.catalog import Catalog
from causalplan.studies.analysis import analyse
from causalplan.studies.misconceptions import check_misconceptions
from causalplan.studies.trials import read_study

RULES = ["provide electricity AND turn electricity into light AND diffuse light CAUSES light"]
STORED = {  # trained on the desk lamp and the flashlight, as the research page exports it
    "goal": "light",
    "functions": {
        "desk_lamp": {
            "base_with_cables": ["provide electricity"],
            "light_bulb": ["turn electricity into light"],
            "shade": ["diffuse light"],
        },
        "flashlight": {
            "batteries": ["provide electricity"],
            "head": ["turn electricity into light", "diffuse light"],
        },
    },
    "rules": RULES,
}


def test_the_shades_diffuse_light_is_found_on_the_desk_lamp_of_a_two_object_model(catalog: Catalog) -> None:
    merged = {
        "object": "desk_lamp_and_flashlight",
        "goal": "light",
        "functions": {
            f"{o}.{part}": labels for o, parts in STORED["functions"].items() for part, labels in parts.items()
        },
        "rules": RULES,
    }
    for document in (STORED, merged):
        check = check_misconceptions(document, catalog, ["desk_lamp", "flashlight"])
        assert check.not_checked is None
        # the flashlight's head is needed (it closes the circuit): only the desk lamp's shade is the misconception
        assert [(m.object_id, m.function, m.parts) for m in check.found] == [("desk_lamp", "diffuse light", ("shade",))]


def test_a_model_that_cannot_be_checked_says_why(catalog: Catalog) -> None:
    check = check_misconceptions({**STORED, "rules": ["light CAUSES light"]}, catalog, ["desk_lamp", "flashlight"])
    assert check.found == () and check.not_checked is not None and check.not_checked.startswith("its model is invalid")


def _trial(participant: str, model: dict[str, Any] | None) -> dict[str, Any]:
    return {
        "trial_id": f"{participant}-1",
        "participant_id": participant,
        "condition": "near",
        "training_order": ["desk_lamp", "flashlight"],
        "test_object": "headlamp",
        "position": 1,
        "verdict": "fails",
        "model": model,
    }


def test_the_analysis_counts_the_far_designs_misconceptions_and_names_what_it_skipped(catalog: Catalog) -> None:
    export = {"trials": [_trial("two-objects", STORED), _trial("no-model", None)]}
    analysis = analyse(read_study(export, catalog), catalog)
    assert list(analysis.misconceptions) == ["two-objects"]
    assert analysis.misconceptions_not_checked == {"no-model": "the export has no model for the participant"}
    assert analysis.as_dict()["misconceptions_not_checked"] == analysis.misconceptions_not_checked
    said = " ".join(analysis.conclusions)
    assert "1 of 1 participants whose models were checked made a function" in said
    assert "not looked for in 1 of 2 participants' models: the export has no model for the participant (1)" in said
