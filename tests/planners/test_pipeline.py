"""The planning pipeline: compile, search, replay; honest statuses and timings."""

from __future__ import annotations

import pytest

from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task
from causalplan.planners.pipeline import PRECHECK, UnknownPlannerError, plan_task
from causalplan.planners.result import PlanStatus
from tests.conftest import example_mapping, example_model

PAPER_PLANS = {
    ("paper/desk_lamp.yaml", None): ["Screw the light bulb into the base with cables."],
    ("paper/failed_desk_lamp.yaml", None): [
        "Screw the light bulb into the base with cables.",
        "Clip the shade onto the base with cables.",
    ],
    ("near/candle.yaml", None): ["Insert the wick into the wax.", "Light the wick with the match."],
    ("paper/desk_lamp.yaml", "paper/flashlight_mapping.yaml"): [
        "Insert the batteries into the case.",
        "Screw the head onto the case.",
    ],
    ("near/candle.yaml", "near/kerosene_lamp_mapping.yaml"): [
        "Screw the burner onto the fuel tank with kerosene.",
        "Thread the wick through the burner into the fuel.",
        "Light the wick with the lighter.",
    ],
}


@pytest.mark.parametrize("planner", ["fd", "fd-opt"])
@pytest.mark.parametrize(("model_file", "mapping_file"), sorted(PAPER_PLANS, key=str))
def test_paper_tasks_give_the_expected_plans(
    model_file: str, mapping_file: str | None, planner: str, catalog: Catalog
) -> None:
    model = example_model(model_file, catalog)
    mapping = example_mapping(mapping_file, catalog) if mapping_file else None
    task = build_task(model, catalog.get(mapping.object_id if mapping else model.object_id), mapping)
    result = plan_task(task, planner)
    assert result.status is PlanStatus.SOLVED
    assert result.planner_used == planner
    assert [step.text for step in result.steps] == PAPER_PLANS[(model_file, mapping_file)]
    assert result.valid_under_model and result.valid_under_true_mechanism
    assert {"compile", "translate", "search", "replay", "total"} <= set(result.timing)
    stages = [seconds for stage, seconds in result.timing.items() if stage != "total"]
    assert all(seconds > 0 for seconds in stages)
    assert sum(stages) <= result.timing["total"]  # the stages run one after another, inside the total


def test_a_goal_out_of_reach_is_decided_before_search(catalog: Catalog) -> None:
    model = example_model("paper/failed_desk_lamp.yaml", catalog)
    mapping = example_mapping("paper/failed_flashlight_mapping.yaml", catalog)
    result = plan_task(build_task(model, catalog.get("flashlight"), mapping))
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.planner_used == PRECHECK
    assert "translate" not in result.timing


def test_unknown_planner_is_a_clear_error(catalog: Catalog) -> None:
    task = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    with pytest.raises(UnknownPlannerError, match="choose one of: auto, fd, fd-opt, mdp"):
        plan_task(task, "magic")


def test_pddl_is_returned_on_request(catalog: Catalog) -> None:
    task = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    assert plan_task(task).pddl is None
    pddl = plan_task(task, include_pddl=True).pddl
    assert pddl is not None and "(:derived" in pddl["domain"] and "(:goal" in pddl["problem"]
