"""Plans to simulate: from a planner's result or a plan file, checked against the object."""

from __future__ import annotations

import pytest

from causalplan.objects.catalog import Catalog
from causalplan.planners.result import PlanStep
from causalplan.sim import PlanInputError, StepRequest, read_plan_steps
from causalplan.sim.plan_steps import check_steps

PLAN_JSON = {
    "status": "solved",
    "object": "flashlight",
    "plan": [
        {"action": "insert", "args": ["batteries", "case"], "fit": "batteries_into_bay", "text": "..."},
        {"action": "screw", "args": ["head", "case"], "fit": "head_onto_case"},
    ],
}


def test_plan_json_output_and_its_plan_list_are_both_read(catalog: Catalog) -> None:
    flashlight = catalog.get("flashlight")
    expected = (
        StepRequest("insert", "batteries", "case", "batteries_into_bay"),
        StepRequest("screw", "head", "case", "head_onto_case"),
    )
    assert read_plan_steps(PLAN_JSON, flashlight) == expected
    assert read_plan_steps(PLAN_JSON["plan"], flashlight) == expected


def test_planner_steps_become_requests(catalog: Catalog) -> None:
    step = PlanStep("screw", ("light_bulb", "base_with_cables"), "bulb_into_socket", "Screw ...")
    assert check_steps([step], catalog.get("desk_lamp")) == (
        StepRequest("screw", "light_bulb", "base_with_cables", "bulb_into_socket"),
    )


@pytest.mark.parametrize(
    ("data", "words"),
    [
        ({"object": "desk_lamp", "plan": []}, "for the object 'desk_lamp', not the flashlight"),
        ({"status": "unsolvable", "plan": None}, r"holds no plan \(status: unsolvable\)"),
        ({"status": "solved"}, "no 'plan' list"),
        ("insert batteries", "A plan is a list of steps"),
        ([["insert"]], "step 1 is not an object"),
        ([{"action": "insert", "args": ["batteries"]}], "step 1: 'args' must be two part ids"),
        ([{"args": ["batteries", "case"]}], "step 1 needs 'action'"),
        ([{"action": "insert", "args": ["batteries", "case"], "how": "fast"}], "unknown field"),
        ([{"action": "weld", "args": ["batteries", "case"]}], "unknown action 'weld'"),
        ([{"action": "insert", "args": ["bulb", "case"]}], "the moving part 'bulb' is not a part of the flashlight"),
        ([{"action": "insert", "args": ["case", "case"]}], "joins the part 'case' to itself"),
        ([{"action": "insert", "args": ["batteries", "case"], "fit": "glue"}], "unknown fit 'glue'"),
        (
            [{"action": "screw", "args": ["batteries", "case"], "fit": "batteries_into_bay"}],
            "is 'insert' with args \\[batteries, case\\], not 'screw'",
        ),
    ],
)
def test_bad_plans_are_refused_with_the_step_and_the_reason(data: object, words: str, catalog: Catalog) -> None:
    with pytest.raises(PlanInputError, match=words) as raised:
        read_plan_steps(data, catalog.get("flashlight"))
    assert raised.value.code == "invalid_plan"


def test_a_step_without_a_fit_is_described_by_its_primitive(catalog: Catalog) -> None:
    assert StepRequest("insert", "batteries", "head").text(catalog.get("flashlight")) == (
        "Insert the batteries into the head."
    )
