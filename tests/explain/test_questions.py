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
