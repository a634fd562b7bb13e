"""The why-not grammar: questions become constraints of catalog ids, or errors with stable codes."""

from __future__ import annotations

import pytest

from causalplan.explain.questions import Kind, Question, QuestionError, parse_question
from causalplan.objects.catalog import Catalog
from causalplan.planners.result import PlanStep

STEPS = (
    PlanStep("screw", ("light_bulb", "base_with_cables"), "bulb_into_socket", "Screw the light bulb into the base."),
    PlanStep("clip", ("shade", "base_with_cables"), "shade_onto_ring", "Clip the shade onto the base."),
)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("attach shade", Question(Kind.ATTACH, ("shade",))),
        ("Why not attach the light bulb?", Question(Kind.ATTACH, ("light_bulb",))),
        ("leave out the shade", Question(Kind.LEAVE_OUT, ("shade",))),
        ("leave out step 1", Question(Kind.LEAVE_OUT, ("light_bulb",))),
        ("shade before light_bulb", Question(Kind.ORDER, ("shade", "light_bulb"))),
        ("use fit shade_onto_ring", Question(Kind.USE_FIT, ("shade",), "shade_onto_ring")),
    ],
)
def test_questions_are_read(catalog: Catalog, text: str, expected: Question) -> None:
    assert parse_question(text, catalog.get("desk_lamp"), STEPS) == expected


def test_an_order_becomes_an_ordering_constraint(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    constraints = parse_question("shade before light bulb", lamp, STEPS).constraints(lamp)
    assert constraints.orderings == frozenset({("shade", "light_bulb")})
    assert constraints.all_required() == {"shade", "light_bulb"}


@pytest.mark.parametrize(
    ("text", "code"),
    [
        ("attach batteries", "unknown_part"),
        ("leave out step 3", "unknown_step"),
        ("use fit glue", "unknown_fit"),
        ("attach base with cables", "invalid_question"),
        ("shade before shade", "invalid_question"),
        ("make it brighter", "invalid_question"),
        ("attach " + "x" * 300, "invalid_question"),
    ],
)
def test_invalid_questions_have_stable_codes(catalog: Catalog, text: str, code: str) -> None:
    with pytest.raises(QuestionError) as raised:
        parse_question(text, catalog.get("desk_lamp"), STEPS)
    assert raised.value.code == code


FLASHLIGHT_STEPS = (
    PlanStep("insert", ("batteries", "case"), "batteries_into_bay", "Insert the batteries into the case."),
    PlanStep("screw", ("head", "case"), "head_onto_case", "Screw the head onto the case."),
)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("why not put the shade on first?", Question(Kind.ORDER, ("shade", "light_bulb"))),
        ("Why not leave out the base?", Question(Kind.LEAVE_OUT, ("base_with_cables",))),
        ("what if the bulb went in last?", Question(Kind.ORDER, ("shade", "light_bulb"))),
        ("why don't you skip the lampshade", None),  # no part is called that: not understood
        ("how about the bulb after the shade?", Question(Kind.ORDER, ("shade", "light_bulb"))),
        ("why not put the shades on", Question(Kind.ATTACH, ("shade",))),
    ],
)
def test_plain_questions_are_read_by_the_parts_names_and_the_question_words(
    catalog: Catalog, text: str, expected: Question | None
) -> None:
    lamp = catalog.get("desk_lamp")
    if expected is None:
        with pytest.raises(QuestionError):
            parse_question(text, lamp, STEPS)
    else:
        assert parse_question(text, lamp, STEPS) == expected


def test_plain_questions_on_the_flashlight(catalog: Catalog) -> None:
    flashlight = catalog.get("flashlight")
    assert parse_question("why not put the head on first?", flashlight, FLASHLIGHT_STEPS) == Question(
        Kind.ORDER, ("head", "batteries")
    )
    assert parse_question("what if the battery went in last?", flashlight, FLASHLIGHT_STEPS) == Question(
        Kind.ORDER, ("head", "batteries")
    )
    assert parse_question("why not leave out the case?", flashlight, FLASHLIGHT_STEPS) == Question(
        Kind.LEAVE_OUT, ("case",)
    )


def test_a_question_not_understood_comes_with_the_closest_answerable_ones_in_words(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    with pytest.raises(QuestionError) as raised:
        parse_question("could the shade be nicer", lamp, STEPS)
    suggestions = raised.value.details["suggestions"]
    assert isinstance(suggestions, list) and len(suggestions) == 3
    assert all("shade" in suggestion and "_" not in suggestion for suggestion in suggestions)
    for suggestion in suggestions:  # each one can be asked as it is
        parse_question(suggestion, lamp, STEPS)
    with pytest.raises(QuestionError) as unknown:
        parse_question("attach the wick", lamp, STEPS)
    assert "_" not in unknown.value.message and unknown.value.details["suggestions"]
