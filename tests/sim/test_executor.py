"""Plans run in physics: correct plans pass, known-bad plans fail at the right step for the right reason."""

from __future__ import annotations

import pytest

from causalplan.objects.catalog import Catalog
from causalplan.sim import RenderMode, SimulationReport, simulate_plan
from causalplan.sim.checks import ALIGNMENT_TOLERANCE_MM, PENETRATION_TOLERANCE_MM, STABILITY_TOLERANCE_MM
from causalplan.sim.outcomes import Failure, StepStatus
from tests.sim.fixtures import CORRECT_PLANS, PEG_BOARD, WALL_SHELF, parsed_object, steps


def run(catalog: Catalog, object_id: str, *items: str) -> SimulationReport:
    return simulate_plan(catalog.get(object_id), steps(*items), render=RenderMode.NONE)


def check(report: SimulationReport, step: int, name: str) -> float:
    """Return the measured figure of a named check of a step."""
    found = next(item for item in report.steps[step - 1].checks if item.name == name)
    assert found.measured is not None
    return found.measured


@pytest.mark.parametrize("object_id", sorted(CORRECT_PLANS))
def test_a_correct_plan_passes_for_each_paper_object(object_id: str, catalog: Catalog) -> None:
    report = simulate_plan(catalog.get(object_id), CORRECT_PLANS[object_id], render=RenderMode.NONE)
    assert report.passed, report.explanation()
    assert [step.status for step in report.steps] == [StepStatus.PASSED] * len(CORRECT_PLANS[object_id])
    assert report.produces_goal and report.is_stable
    assert all(requirement.met for requirement in report.requirements)
    for number in range(1, len(report.steps) + 1):
        assert check(report, number, "path") <= PENETRATION_TOLERANCE_MM
        assert check(report, number, "alignment") <= ALIGNMENT_TOLERANCE_MM


def test_the_same_plan_gives_the_same_report_twice(catalog: Catalog) -> None:
    plan = CORRECT_PLANS["kerosene_lamp"]
    first = simulate_plan(catalog.get("kerosene_lamp"), plan, render=RenderMode.NONE)
    second = simulate_plan(catalog.get("kerosene_lamp"), plan, render=RenderMode.NONE)
    assert first == second
    assert first.as_dict() | {"timing_ms": None} == second.as_dict() | {"timing_ms": None}


def test_drawing_pictures_does_not_change_the_physics(catalog: Catalog) -> None:
    plan = CORRECT_PLANS["desk_lamp"]
    assert simulate_plan(catalog.get("desk_lamp"), plan, render=RenderMode.NONE) == simulate_plan(
        catalog.get("desk_lamp"), plan, render=RenderMode.FINAL, size=(160, 120)
    )


def test_the_head_screwed_on_before_the_batteries_blocks_their_path(catalog: Catalog) -> None:
    report = run(catalog, "flashlight", "screw head case head_onto_case", "insert batteries case batteries_into_bay")
    failed = report.failed_step
    assert failed is not None and failed.number == 2
    assert failed.failure is Failure.BLOCKED_PATH
    assert "blocked by the head" in failed.message
    assert check(report, 2, "path") > PENETRATION_TOLERANCE_MM
    assert report.unmet_requirements == ("the batteries are in the case",)
    assert not report.produces_goal


def test_the_shade_before_the_bulb_blocks_the_bulb(catalog: Catalog) -> None:
    report = run(
        catalog, "desk_lamp", "clip shade base_with_cables shade_onto_ring", "screw light_bulb base_with_cables"
    )
    failed = report.failed_step
    assert failed is not None and (failed.number, failed.failure) == (2, Failure.BLOCKED_PATH)
    assert "blocked by the shade" in failed.message


def test_the_chimney_before_lighting_blocks_the_lighter(catalog: Catalog) -> None:
    plan = CORRECT_PLANS["kerosene_lamp"]
    report = simulate_plan(catalog.get("kerosene_lamp"), (*plan[:2], plan[3], plan[2]), render=RenderMode.NONE)
    failed = report.failed_step
    assert failed is not None and (failed.number, failed.failure) == (4, Failure.BLOCKED_PATH)
    assert "glass chimney" in failed.message
    assert report.unmet_requirements == ("the wick has been lit",)


def test_an_incompatible_connector_fails_before_anything_moves(catalog: Catalog) -> None:
    report = run(catalog, "flashlight", "screw head case head_onto_case", "insert batteries head")
    failed = report.failed_step
    assert failed is not None and (failed.number, failed.failure) == (2, Failure.INCOMPATIBLE_CONNECTORS)
    assert "2 x AA" in failed.message and "M30 thread" in failed.message


def test_a_step_without_a_fit_finds_matching_connectors(catalog: Catalog) -> None:
    report = run(catalog, "flashlight", "insert batteries case", "screw head case")
    assert report.passed
    assert [requirement.fit for requirement in report.requirements] == ["batteries_into_bay", "head_onto_case"]


def test_attaching_to_a_part_not_in_the_assembly_is_a_missing_part(catalog: Catalog) -> None:
    report = run(catalog, "kerosene_lamp", "insert wick burner wick_into_burner", "screw burner fuel_tank")
    failed = report.failed_step
    assert failed is not None and (failed.number, failed.failure) == (1, Failure.MISSING_PART)
    assert report.steps[1].status is StepStatus.NOT_RUN


def test_a_plan_missing_a_part_runs_but_does_not_produce_light(catalog: Catalog) -> None:
    report = run(catalog, "flashlight", "screw head case head_onto_case")
    assert report.failed_step is None and report.is_stable
    assert not report.produces_goal and not report.passed
    assert report.unmet_requirements == ("the batteries are in the case",)


def test_attaching_a_part_twice_is_refused(catalog: Catalog) -> None:
    report = run(catalog, "candle", "insert wick wax wick_into_wax", "insert wick wax wick_into_wax")
    failed = report.failed_step
    assert failed is not None and (failed.number, failed.failure) == (2, Failure.ALREADY_ATTACHED)


def test_a_peg_too_thick_for_its_hole_is_welded_misaligned() -> None:
    board = parsed_object(PEG_BOARD)
    good = simulate_plan(board, steps("insert thin_peg board thin_peg_into_hole"), render=RenderMode.NONE)
    assert good.passed
    bad = simulate_plan(board, steps("insert thick_peg board thick_peg_into_hole"), render=RenderMode.NONE)
    failed = bad.failed_step
    assert failed is not None and (failed.number, failed.failure) == (1, Failure.MISALIGNED)
    assert "stopped against the board" in failed.message
    assert check(bad, 1, "alignment") == pytest.approx(30.0, abs=1.0)
    assert not bad.produces_goal


def test_a_part_placed_without_fastening_falls() -> None:
    shelf = parsed_object(WALL_SHELF)
    report = simulate_plan(shelf, steps("place plank post plank_against_bracket"), render=RenderMode.NONE)
    failed = report.failed_step
    assert failed is not None and (failed.number, failed.failure) == (1, Failure.FALLS)
    assert "the plank fell" in failed.message
    assert check(report, 1, "stability") > STABILITY_TOLERANCE_MM
    screwed = simulate_plan(shelf, steps("screw plank post plank_screwed_to_bracket"), render=RenderMode.NONE)
    assert screwed.passed


def test_a_user_object_without_geometry_is_simulated_with_boxes(user_catalog: Catalog) -> None:
    report = simulate_plan(
        user_catalog.get("bedside_lamp"),
        steps("screw warm_bulb lamp_body warm_bulb_into_socket", "screw cool_bulb lamp_body"),
        render=RenderMode.NONE,
    )
    assert report.steps[0].status is StepStatus.PASSED
    failed = report.failed_step
    assert failed is not None and (failed.number, failed.failure) == (2, Failure.BLOCKED_PATH)
    assert "warm bulb" in failed.message
    assert report.produces_goal  # the warm bulb alone lights the lamp
