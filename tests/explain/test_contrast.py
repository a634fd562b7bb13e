"""Why not …? Known answers on the paper's failed desk-lamp model and its working one."""

from __future__ import annotations

import pytest

from causalplan.explain.contrast import why_not
from causalplan.explain.questions import parse_question
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanResult
from tests.conftest import example_model


def _planned(catalog: Catalog, model: str) -> tuple[PlanningTask, PlanResult]:
    task = build_task(example_model(model, catalog), catalog.get("desk_lamp"))
    return task, plan_task(task, "fd", val=True)


def test_the_shade_goes_after_the_bulb_because_it_covers_the_socket(catalog: Catalog) -> None:
    # "Why does the robot attach the shade after the bulb?" = why not the shade before the bulb.
    task, plan = _planned(catalog, "paper/failed_desk_lamp.yaml")
    assert [step.args[0] for step in plan.steps] == ["light_bulb", "shade"]
    answer = why_not(task, parse_question("shade before light_bulb", task.obj, plan.steps), plan)
    assert answer.code == "blocked"
    assert answer.decided_by == {
        "fit": "shade_onto_ring",
        "rules_out": "bulb_into_socket",
        "connector": "base_with_cables.socket",
    }
    assert "the shade covers the socket of the base with cables and the light bulb cannot go in" in answer.message
    assert not answer.alternative.has_plan


@pytest.mark.slow
def test_the_simulator_names_the_blocked_order(catalog: Catalog) -> None:
    task, plan = _planned(catalog, "paper/failed_desk_lamp.yaml")
    answer = why_not(task, parse_question("shade before light_bulb", task.obj, plan.steps), plan, simulate=True)
    assert answer.simulation_failure == "blocked_path"
    assert "(blocked_path)" not in answer.message and "blocked_path" in answer.message


def test_leaving_the_shade_out_loses_light_by_rule_one(catalog: Catalog) -> None:
    task, plan = _planned(catalog, "paper/failed_desk_lamp.yaml")
    answer = why_not(task, parse_question("why not leave out the shade?", task.obj, plan.steps), plan)
    assert answer.code == "goal_unreachable"
    assert answer.decided_by == {"function": "diffuse light", "rules": [1]}
    assert answer.message.startswith("Then light cannot be produced: rule 1 (")
    assert "needs 'diffuse light', and only the shade carries it" in answer.message


def test_the_working_model_does_not_need_the_shade(catalog: Catalog) -> None:
    task, plan = _planned(catalog, "paper/desk_lamp.yaml")
    answer = why_not(task, parse_question("attach shade", task.obj, plan.steps), plan)
    assert answer.code == "not_needed"
    assert "does not need it for light" in answer.message
    # The alternative is a plan like any other: replayed, VAL-checked, and it attaches the shade.
    assert answer.alternative.validated_by == {"replay": "valid", "val": "valid"}
    assert [step.args[0] for step in answer.alternative.steps] == ["light_bulb", "shade"]


def test_an_unused_label_is_named(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    labelling = type(model.labelling)("desk_lamp", {**model.labelling.functions, "shade": ("diffuse light",)})
    task = build_task(model, catalog.get("desk_lamp"), labelling)
    plan = plan_task(task, "fd")
    answer = why_not(task, parse_question("attach shade", task.obj, plan.steps), plan)
    assert "your model does not need the shade for light: no rule uses 'diffuse light'" in answer.message.lower()


def test_a_question_the_plan_already_answers(catalog: Catalog) -> None:
    task, plan = _planned(catalog, "paper/failed_desk_lamp.yaml")
    answer = why_not(task, parse_question("light_bulb before shade", task.obj, plan.steps), plan)
    assert answer.code == "already_does"
    assert answer.alternative is plan
