"""``causalplan simulate``: plans (or reads a plan), runs it in physics, prints and draws what happened."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner, Result

from causalplan.cli import app
from tests.conftest import EXAMPLES

DESK_LAMP = EXAMPLES / "paper" / "desk_lamp.yaml"
FLASHLIGHT_MAPPING = EXAMPLES / "paper" / "flashlight_mapping.yaml"
FAILED_DESK_LAMP = EXAMPLES / "paper" / "failed_desk_lamp.yaml"
FAILED_FLASHLIGHT_MAPPING = EXAMPLES / "paper" / "failed_flashlight_mapping.yaml"
PLANS = EXAMPLES / "plans"

runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "200"})


def run(*args: object) -> Result:
    result = runner.invoke(app, [str(arg) for arg in args])
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    return result


def run_json(*args: object) -> tuple[int, dict[str, Any]]:
    result = run(*args, "--json")
    return result.exit_code, json.loads(result.stdout)


def test_without_a_plan_it_plans_first_then_simulates() -> None:
    result = run("simulate", DESK_LAMP)
    assert result.exit_code == 0
    assert "1. Screw the light bulb into the base with cables. passed" in result.stdout
    assert "Produces light: yes" in result.stdout


def test_a_mapping_simulates_the_other_object_as_json() -> None:
    code, data = run_json("simulate", DESK_LAMP, "--mapping", FLASHLIGHT_MAPPING)
    assert code == 0
    assert data["object"] == "flashlight" and data["passed"] and data["files"] == []
    assert [step["fit"] for step in data["steps"]] == ["batteries_into_bay", "head_onto_case"]


def test_a_plan_file_from_the_examples_runs_and_draws(tmp_path: Path) -> None:
    png = tmp_path / "lamp.png"
    result = run("simulate", DESK_LAMP, "--plan", PLANS / "desk_lamp_with_shade.json", "--png", png)
    assert result.exit_code == 0
    assert "2. Clip the shade onto the base with cables. passed" in result.stdout
    assert png.read_bytes().startswith(b"\x89PNG\r\n\x1a\n")
    assert f"Wrote {png}" in result.stdout


def test_a_known_bad_plan_fails_with_exit_1_and_says_where() -> None:
    result = run("simulate", DESK_LAMP, "--plan", PLANS / "desk_lamp_shade_first.json")
    assert result.exit_code == 1
    assert "2. Screw the light bulb into the base with cables. FAILED[blocked_path]: " in result.stdout
    assert "blocked by the shade" in result.stdout
    assert "Produces light: no" in result.stdout


def test_the_flashlight_example_plan_screws_the_head_on_too_early() -> None:
    code, data = run_json(
        "simulate", DESK_LAMP, "--mapping", FLASHLIGHT_MAPPING, "--plan", PLANS / "flashlight_head_first.json"
    )
    assert code == 1
    assert (data["steps"][1]["status"], data["steps"][1]["failure"]) == ("failed", "blocked_path")


def test_the_output_of_plan_json_is_a_plan_file(tmp_path: Path) -> None:
    planned = run("plan", DESK_LAMP, "--mapping", FLASHLIGHT_MAPPING, "--json")
    assert planned.exit_code == 0
    plan_file = tmp_path / "plan.json"
    plan_file.write_text(planned.stdout, encoding="utf-8")
    code, data = run_json("simulate", DESK_LAMP, "--mapping", FLASHLIGHT_MAPPING, "--plan", plan_file)
    assert code == 0 and data["produces_goal"]


@pytest.mark.slow
def test_frames_and_a_gif(tmp_path: Path) -> None:
    frames, gif = tmp_path / "frames", tmp_path / "steps.gif"
    result = run("simulate", DESK_LAMP, "--frames", frames, "--gif", gif)
    assert result.exit_code == 0
    assert sorted(path.name for path in frames.iterdir()) == ["step_00.png", "step_01.png", "step_02.png", "strip.png"]
    assert gif.read_bytes()[:6] == b"GIF89a"


def test_the_arm_reports_reach_per_step() -> None:
    code, data = run_json("simulate", DESK_LAMP, "--arm")
    assert code == 0 and data["arm"]
    assert data["steps"][0]["reach"]["reachable"] is True


def test_a_plan_with_an_unknown_fit_is_invalid_input(tmp_path: Path) -> None:
    plan_file = tmp_path / "plan.json"
    plan_file.write_text(json.dumps([{"action": "screw", "args": ["light_bulb", "shade"], "fit": "glue"}]))
    result = run("simulate", DESK_LAMP, "--plan", plan_file)
    assert result.exit_code == 2
    assert "invalid_plan" in result.stderr and "unknown fit 'glue'" in result.stderr


def test_a_plan_with_wrong_args_is_invalid_input(tmp_path: Path) -> None:
    plan_file = tmp_path / "plan.json"
    plan_file.write_text(json.dumps([{"action": "screw", "args": ["light_bulb"], "fit": "bulb_into_socket"}]))
    result = run("simulate", DESK_LAMP, "--plan", plan_file)
    assert result.exit_code == 2
    assert "'args' must be two part ids" in result.stderr


def test_a_plan_file_that_is_not_json_or_missing_is_invalid_input(tmp_path: Path) -> None:
    plan_file = tmp_path / "plan.json"
    plan_file.write_text("steps: [screw]")
    not_json = run("simulate", DESK_LAMP, "--plan", plan_file)
    assert not_json.exit_code == 2 and "is not JSON" in not_json.stderr
    missing = run("simulate", DESK_LAMP, "--plan", tmp_path / "nothing.json")
    assert missing.exit_code == 2 and "Cannot read the plan file" in missing.stderr


def test_no_plan_means_nothing_to_simulate() -> None:
    code, data = run_json("simulate", FAILED_DESK_LAMP, "--mapping", FAILED_FLASHLIGHT_MAPPING)
    assert code == 1
    assert data["status"] == "unsolvable" and data["simulation"] is None


def test_an_unwritable_picture_is_a_clear_error(tmp_path: Path) -> None:
    result = run("simulate", DESK_LAMP, "--png", tmp_path / "no_such_folder" / "lamp.png")
    assert result.exit_code == 2
    assert "output_not_writable" in result.stderr


def test_the_robot_builds_the_lamp_and_writes_its_motor_commands(tmp_path: Path) -> None:
    from causalplan.sim.robot.trajectory import read_trajectory

    commands = tmp_path / "trajectory.json"
    code, data = run_json("simulate", DESK_LAMP, "--robot", "--trajectory", commands)
    assert code == 0 and data["produces_goal"]
    assert data["steps"][0]["robot"][:5] == ["transit", "grasp", "carry", "approach", "screw"]
    assert data["robot"]["seconds"] > data["robot"]["unconstrained_seconds"] > 1
    assert data["robot"]["motors"]["produces_goal"] and data["robot"]["motors"]["failure"] is None
    assert data["robot"]["motors"]["tracking"]["max_end_effector_error_mm"] >= 0
    assert data["files"] == [str(commands)]
    trajectory = read_trajectory(json.loads(commands.read_text()))
    assert round(trajectory.seconds, 2) == data["robot"]["seconds"]
    checked = run("check-trajectory", commands)
    assert checked.exit_code == 0 and "within the panda's limits" in checked.stdout


def test_the_robot_report_says_what_the_robot_did_per_step() -> None:
    result = run("simulate", DESK_LAMP, "--robot")
    assert result.exit_code == 0
    assert "robot: transit, grasp, carry, approach, screw, release" in result.stdout
    assert "The robot moves for" in result.stdout and "Driven by its motors: produces light" in result.stdout


def test_a_part_out_of_reach_fails_the_step_with_unreachable() -> None:
    model = EXAMPLES / "robot" / "long_bench.yaml"
    code, data = run_json("simulate", model, "--robot", "--catalog", EXAMPLES / "robot" / "catalog")
    assert code == 1
    assert data["steps"][0]["failure"] == "unreachable"


def test_a_seat_walled_in_fails_the_step_with_no_collision_free_path() -> None:
    model = EXAMPLES / "robot" / "walled_plate.yaml"
    result = run("simulate", model, "--robot", "--catalog", EXAMPLES / "robot" / "catalog")
    assert result.exit_code == 1
    assert "FAILED[no_collision_free_path]" in result.stdout


def test_video_and_trajectory_need_the_robot_and_a_known_format(tmp_path: Path) -> None:
    no_robot = run("simulate", DESK_LAMP, "--video", tmp_path / "lamp.mp4")
    assert no_robot.exit_code == 2 and "need --robot" in no_robot.stderr
    no_robot = run("simulate", DESK_LAMP, "--ros2-bag", tmp_path / "bag")
    assert no_robot.exit_code == 2 and "need --robot" in no_robot.stderr
    avi = run("simulate", DESK_LAMP, "--robot", "--video", tmp_path / "lamp.avi")
    assert avi.exit_code == 2 and "writes .mp4 or .gif, not '.avi'" in avi.stderr
    both = run("simulate", DESK_LAMP, "--robot", "--arm")
    assert both.exit_code == 2 and "not both" in both.stderr


@pytest.mark.slow
def test_estimate_fits_reports_each_fit_with_its_interval_and_failures(tmp_path: Path) -> None:
    overlay = tmp_path / "overlay.yaml"
    code, data = run_json("estimate-fits", "desk_lamp", "--trials", 50, "--seed", 3, "--out", overlay)
    assert code == 0
    assert [fit["id"] for fit in data["fits"]] == ["bulb_into_socket", "shade_onto_ring"]
    for fit in data["fits"]:
        assert set(fit) == {"id", "trials", "successes", "probability", "interval", "failures"}
        assert fit["trials"] == 50 and fit["interval"][0] <= fit["probability"] <= fit["interval"][1]
    planned = run("plan", DESK_LAMP, "--planner", "mdp", "--catalog-overlay", overlay)
    thread = data["fits"][0]["probability"]
    assert f"Success probability {thread:.4f}" in planned.stdout


def test_estimate_fits_names_an_unknown_object_or_fit() -> None:
    unknown = run("estimate-fits", "desk_lamb")
    assert unknown.exit_code == 2 and "Did you mean 'desk_lamp'?" in unknown.stderr
    no_fit = run("estimate-fits", "desk_lamp", "--fit", "glue")
    assert no_fit.exit_code == 2 and "has no fit 'glue'" in no_fit.stderr


def test_a_wrong_overlay_is_invalid_input(tmp_path: Path) -> None:
    overlay = tmp_path / "overlay.yaml"
    overlay.write_text("objects: {desk_lamp: {bulb_into_socket: {probability: 2}}}")
    result = run("plan", DESK_LAMP, "--catalog-overlay", overlay)
    assert result.exit_code == 2 and "probability 2 is not in (0, 1]" in result.stderr


def test_check_trajectory_refuses_an_over_fast_file_naming_the_joint_and_the_ratio(tmp_path: Path) -> None:
    home = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
    points = [
        {"time_from_start": k * 0.01, "positions": [*home[:6], home[6] + 0.0522 * k]} for k in range(5)
    ]  # joint 7 at 5.22 rad/s: twice its limit
    fast = tmp_path / "fast.json"
    fast.write_text(json.dumps({"joints": [f"panda_joint{i}" for i in range(1, 8)], "points": points}))
    result = run("check-trajectory", fast)
    assert result.exit_code == 1  # beyond the limits is a "no", not invalid input
    assert "panda_joint7 velocity" in result.stdout and "2.00x its limit 2.61" in result.stdout
    code, data = run_json("check-trajectory", fast, "--robot", "panda")
    assert code == 1 and not data["within_limits"]
    velocity = [v for v in data["violations"] if v["quantity"] == "velocity"]
    assert velocity[0]["joint"] == "panda_joint7" and velocity[0]["ratio"] == 2.0 and velocity[0]["time"] == 0.005


def test_check_trajectory_says_what_is_wrong_with_a_bad_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"robot": "franka_panda", "joints": [], "rate_hz": 50, "segments": []}))
    result = run("check-trajectory", bad)
    assert result.exit_code == 2 and "invalid_trajectory" in result.stderr and "first format" in result.stderr
    bad.write_text(json.dumps({"joints": [], "points": [{"time_from_start": 0, "positions": []}]}))
    unknown = run("check-trajectory", bad, "--robot", "ur5")
    assert unknown.exit_code == 2 and "unknown_robot" in unknown.stderr


def test_check_trajectory_reads_the_bag_and_the_goal_that_simulate_writes(tmp_path: Path) -> None:
    bag, goal = tmp_path / "bag", tmp_path / "goal.yaml"
    code, data = run_json("simulate", DESK_LAMP, "--robot", "--ros2-bag", bag, "--joint-trajectory", goal)
    assert code == 0 and data["files"] == [str(goal), str(bag)]
    for written in (bag, goal):
        result = run("check-trajectory", written)
        assert result.exit_code == 0, result.output
        assert f"{written}: " in result.stdout and "points within the panda's limits" in result.stdout
        checked = run_json("check-trajectory", written)[1]
        assert checked["within_limits"] and checked["points"] > 100
        assert abs(checked["seconds"] - data["robot"]["seconds"]) < 0.01
    metadata = run("check-trajectory", bag / "metadata.yaml")
    assert metadata.exit_code == 2 and "give the bag's folder instead" in metadata.stderr


def test_check_trajectory_says_what_is_wrong_with_a_folder_or_yaml_that_is_no_trajectory(tmp_path: Path) -> None:
    empty = tmp_path / "not_a_bag"
    empty.mkdir()
    not_a_bag = run("check-trajectory", empty)
    assert not_a_bag.exit_code == 2 and "is not a ROS 2 bag that can be read" in not_a_bag.stderr
    model = run("check-trajectory", DESK_LAMP)
    assert model.exit_code == 2 and "A FollowJointTrajectory goal is YAML with 'trajectory'" in model.stderr
