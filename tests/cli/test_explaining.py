"""`causalplan explain` and `causalplan transfer --repair`: answers in words and JSON, errors with codes."""

from __future__ import annotations

import json

from tests.cli.test_cli import FAILED_DESK_LAMP, FAILED_FLASHLIGHT_MAPPING, run


def test_why_not_the_shade_before_the_bulb() -> None:
    result = run("explain", FAILED_DESK_LAMP, "--why-not", "shade before light_bulb")
    assert result.exit_code == 0, result.output
    assert "[blocked] Then the shade covers the socket of the base with cables" in result.stdout


def test_why_a_step_in_json() -> None:
    result = run("explain", FAILED_DESK_LAMP, "--why", "shade", "--why-not", "leave out the shade", "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    [why] = data["why"]
    assert (why["part"], why["chains"][0]["function"]) == ("shade", "diffuse light")
    assert data["why_not"]["code"] == "goal_unreachable"
    assert data["plan"]["validated_by"] == {"replay": "valid", "val": "valid"}


def test_a_part_the_object_does_not_have_is_an_error() -> None:
    result = run("explain", FAILED_DESK_LAMP, "--why-not", "attach batteries")
    assert result.exit_code == 2
    assert "error[unknown_part]: The desk lamp has no part 'batteries'" in result.stderr


def test_an_unreadable_question_offers_questions_it_can_answer() -> None:
    result = run("explain", FAILED_DESK_LAMP, "--why-not", "make it brighter")
    assert result.exit_code == 2
    assert "error[invalid_question]" in result.stderr and "It can answer, for example:" in result.stderr
    assert "Why not leave out the light bulb?" in result.stderr  # in the object's words, never an id


def test_transfer_repair_lists_the_heads_missing_function() -> None:
    result = run("transfer", FAILED_DESK_LAMP, FAILED_FLASHLIGHT_MAPPING, "--repair", "--json")
    assert result.exit_code == 1
    repairs = json.loads(result.stdout)["repairs"]
    assert repairs["found"] >= 2 and repairs["by_size"]["1"] >= 1
    assert any(
        (edit["kind"], edit["label"], edit["part"]) == ("give_function", "turn electricity into light", "head")
        for repair in repairs["repairs"]
        for edit in repair["edits"]
    )


def test_transfer_repair_in_words() -> None:
    result = run("transfer", FAILED_DESK_LAMP, FAILED_FLASHLIGHT_MAPPING, "--repair")
    assert result.exit_code == 1
    assert "Repairs: 4 found (1 with 1 edit, 3 with 2 edits), all shown;" in result.stdout
    assert "[1] give 'turn electricity into light' to the batteries" in result.stdout
