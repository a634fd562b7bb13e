"""The robot carries out the plan: every paper object and the toy car built by the Panda, failures named."""

from __future__ import annotations

import json
import math
from functools import cache

import pytest

from causalplan.errors import CatalogError
from causalplan.objects.catalog import load_catalog
from causalplan.sim import SimulationReport, simulate_plan
from causalplan.sim.geometry import solids
from causalplan.sim.outcomes import RenderMode, StepStatus
from causalplan.sim.poses import difference
from causalplan.sim.robot.grasps import grasp_of
from causalplan.sim.robot.panda import JOINT_NAMES
from causalplan.sim.robot.replay import replay
from causalplan.sim.robot.trajectory import SEGMENT_KINDS, read_trajectory
from tests.conftest import EXAMPLES, builtin_catalog
from tests.sim.fixtures import CORRECT_PLANS, PEG_BOARD, TOY_CAR_PLAN, parsed_object, steps

pytestmark = pytest.mark.slow  # the Panda plans and carries out whole assemblies

PLANS = {**CORRECT_PLANS, "toy_car": TOY_CAR_PLAN}


@cache
def robot_run(object_id: str) -> SimulationReport:
    """Return the robot's run of the object's whole plan, made once per test session."""
    return simulate_plan(builtin_catalog().get(object_id), PLANS[object_id], render=RenderMode.NONE, robot=True)


@pytest.mark.parametrize("object_id", sorted(PLANS))
def test_the_robot_builds_every_paper_object_and_the_toy_car(object_id: str) -> None:
    report = robot_run(object_id)
    assert report.produces_goal, report.explanation()
    assert report.passed
    for step in report.steps:
        assert step.motions[:3] == ("transit", "grasp", "carry")
        assert step.motions[-2:] == ("release", "retreat")


def test_a_screw_turns_the_wrist_and_regrasps_when_joint_7_runs_out() -> None:
    report = robot_run("desk_lamp")
    motions = report.steps[0].motions
    assert "screw" in motions
    assert motions.count("grasp") >= 2  # two turns of the bulb are more than joint 7's range
    commands = report.motor_commands
    assert commands is not None
    kinds = [segment.kind for segment in commands.segments]
    regrasp = kinds.index("grasp", kinds.index("screw"))  # open, turn back, close: each a motion from rest
    release, turn = commands.segments[regrasp - 2], commands.segments[regrasp - 1]
    assert (release.kind, turn.kind) == ("release", "transit")
    wrist = [point.positions[6] for point in commands.points[turn.first : turn.last + 1]]
    assert abs(wrist[-1] - wrist[0]) == pytest.approx(math.pi, abs=1e-3)
    assert len(wrist) > 20  # turned over many commands, not in one jump


def test_lighting_brings_the_flame_to_the_wick_and_back_to_the_table() -> None:
    report = robot_run("candle")
    assert report.steps[1].motions == ("transit", "grasp", "carry", "approach", "ignite", "carry", "release", "retreat")
    home = report.placed["match"]
    assert home.position[2] < 0.01  # the match lies on the table again


def test_the_trajectory_file_has_the_documented_shape() -> None:
    trajectory = robot_run("flashlight").motor_commands
    assert trajectory is not None
    data = json.loads(json.dumps(trajectory.as_dict()))
    assert data["robot"] == "panda" and data["format"] == "causalplan-trajectory/2"
    assert data["joints"] == list(JOINT_NAMES)
    assert data["limits"]["position_max"][6] == 2.8973 and data["limits"]["safety_factor"] == 0.5
    assert {segment["kind"] for segment in data["segments"]} <= set(SEGMENT_KINDS)
    assert {segment["gripper"] for segment in data["segments"]} == {"open", "closed"}
    assert {segment["step"] for segment in data["segments"]} == {1, 2}
    point = data["points"][1]
    assert {"time_from_start", "positions", "velocities", "accelerations", "gripper_width"} <= set(point)
    assert all(len(point[key]) == 7 for key in ("positions", "velocities", "accelerations"))


@pytest.mark.parametrize("object_id", ["desk_lamp", "candle"])
def test_replaying_the_trajectory_file_in_a_fresh_scene_rebuilds_the_same_assembly(object_id: str) -> None:
    report = robot_run(object_id)
    assert report.motor_commands is not None
    trajectory = read_trajectory(json.loads(json.dumps(report.motor_commands.as_dict())))
    replayed = replay(builtin_catalog().get(object_id), PLANS[object_id], trajectory)
    assert set(replayed) == set(report.placed)
    for part, pose in report.placed.items():
        moved, turned = difference(pose, replayed[part])
        assert moved < 1e-4 and turned < 1e-3, part


def test_the_same_plan_gives_the_same_trajectory() -> None:
    again = simulate_plan(builtin_catalog().get("flashlight"), PLANS["flashlight"], render=RenderMode.NONE, robot=True)
    first = robot_run("flashlight").motor_commands
    assert first is not None and again.motor_commands is not None
    assert again.motor_commands.as_dict() == first.as_dict()


def test_a_part_out_of_the_arms_reach_fails_unreachable_at_step_1() -> None:
    bench = load_catalog([EXAMPLES / "robot" / "catalog"]).get("long_bench")
    report = simulate_plan(bench, steps("insert peg bench peg_onto_bench"), render=RenderMode.NONE, robot=True)
    failed = report.failed_step
    assert failed is not None and failed.number == 1
    assert failed.failure is not None and failed.failure.value == "unreachable"
    assert "above the peg" in failed.message


def test_a_seat_walled_in_fails_with_no_collision_free_path() -> None:
    plate = load_catalog([EXAMPLES / "robot" / "catalog"]).get("walled_plate")
    report = simulate_plan(plate, steps("insert peg plate peg_onto_seat"), render=RenderMode.NONE, robot=True)
    failed = report.failed_step
    assert failed is not None and failed.number == 1
    assert failed.failure is not None and failed.failure.value == "no_collision_free_path"
    assert "walled plate" in failed.message
    assert not report.produces_goal


def test_the_shade_before_the_bulb_blocks_the_bulb_at_the_seat() -> None:
    shade_first = steps("clip shade base_with_cables shade_onto_ring", "screw light_bulb base_with_cables")
    report = simulate_plan(builtin_catalog().get("desk_lamp"), shade_first, render=RenderMode.NONE, robot=True)
    assert report.steps[0].status is StepStatus.PASSED
    failed = report.failed_step
    assert failed is not None and failed.number == 2
    assert failed.failure is not None and failed.failure.value == "blocked_path"
    assert "blocked by the shade" in failed.message


def test_a_part_wider_than_the_gripper_needs_a_grasp_from_the_catalog() -> None:
    lamp = builtin_catalog().get("desk_lamp")
    shade = lamp.part("shade")
    assert not isinstance(grasp_of(shade, solids(lamp)["shade"]), str)  # the catalog's rim grasp
    without = grasp_of(type(shade)(shade.id, shade.name, shade.connectors, shade.geometry), solids(lamp)["shade"])
    assert isinstance(without, str) and "220 mm across" in without


def test_a_default_part_is_held_from_above_at_its_top() -> None:
    board = parsed_object(PEG_BOARD)
    found = grasp_of(board.part("thin_peg"), solids(board)["thin_peg"])
    assert not isinstance(found, str)
    pose, width = found
    assert pose.position == pytest.approx((0.0, 0.0, 0.04))  # 10 mm below the top of a 50 mm peg
    assert width == pytest.approx(0.016)


def test_a_grasp_beside_the_part_holds_nothing_and_the_grasp_is_lost() -> None:
    text = PEG_BOARD.replace(
        "  - id: thin_peg\n    name: thin peg\n",
        "  - id: thin_peg\n    name: thin peg\n    grasp: {at: [0.06, 0, 0.04], fingers: [1, 0, 0]}\n",
    )
    report = simulate_plan(
        parsed_object(text), steps("insert thin_peg board thin_peg_into_hole"), render=RenderMode.NONE, robot=True
    )
    failed = report.failed_step
    assert failed is not None and failed.failure is not None
    assert failed.failure.value == "grasp_lost"
    assert "the grasp holds nothing" in failed.message


@pytest.mark.parametrize(
    ("grasp", "says"),
    [
        ("{at: [0, 0, 0.04], approach: [0, 0, 0]}", "the grasp's approach must not be [0, 0, 0]"),
        ("{at: [0, 0, 0.04], fingers: [0, 0, 1]}", "the grasp's fingers must close at right angles to its approach"),
        ("{at: [0, 0, 0.04], width: 0.2}", "less than or equal to 0.08"),
        ("{approach: [0, 0, -1]}", "grasp > at: Field required"),
    ],
)
def test_a_wrong_catalog_grasp_says_what_is_wrong(grasp: str, says: str) -> None:
    text = PEG_BOARD.replace(
        "  - id: thin_peg\n    name: thin peg\n", f"  - id: thin_peg\n    name: thin peg\n    grasp: {grasp}\n"
    )
    with pytest.raises(CatalogError) as raised:
        parsed_object(text)
    assert says in raised.value.message
