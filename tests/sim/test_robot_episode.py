"""The Panda carries out a troubleshooting episode in physics, action by action."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.objects.catalog import Catalog
from causalplan.sim.robot.checker import violations
from causalplan.sim.robot.motors import SLIP_TOLERANCE_MM, TRACKING_TOLERANCE_MM, TRACKING_TOLERANCE_RAD
from causalplan.sim.robot_episode import robot_episode
from causalplan.sim.robot_episode_playback import episode_playback
from causalplan.sim.spares import SPARE
from causalplan.troubleshoot.episode import Episode, Step
from causalplan.troubleshoot.task import troubleshooting_task
from tests.sim.fixtures import SHADE_BEFORE_BULB, SPARE_SHADE_ONLY

LAMP = Path(__file__).resolve().parents[2] / "examples" / "paper" / "desk_lamp.yaml"


def _distance(a: list[float], b: list[float]) -> float:
    return math.dist(a[:3], b[:3])


def test_the_panda_unscrews_the_bulb_sets_it_aside_and_screws_in_the_spare(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    episode = troubleshooting_task(lamp).episode("oracle", "light_bulb")
    done = [(step.kind, step.part) for step in episode.steps]
    assert done == [
        ("detach", "shade"),
        ("inspect", "light_bulb"),
        ("detach", "light_bulb"),
        ("replace", "light_bulb"),
        ("attach", "light_bulb"),
        ("attach", "shade"),
        ("test", None),
    ]
    run = robot_episode(lamp, episode, tracks=True)
    assert run.produces_goal, run.as_dict()
    motions = [action.motions for action in run.actions]
    assert motions[0][:2] == ("transit", "grasp") and "push" in motions[0]  # the shade's clip, in reverse
    assert "screw" in motions[2] and motions[2][-2:] == ("release", "retreat")  # unscrewed, set down
    assert motions[1] == motions[3] == motions[6] == ()  # looking; the spare waits on the table; the test
    assert "screw" in motions[4] and "push" in motions[5]
    assert run.commands is not None and violations(run.commands) == []
    # The player's document: the broken bulb ends where it was set aside, the spare on the lamp.
    document = episode_playback(lamp, run)
    parts = {part["id"]: part for part in document["parts"]}  # type: ignore[attr-defined]
    assert set(parts) == {"base_with_cables", "light_bulb", "shade", "light_bulb" + SPARE}
    assembled = document["assembled"]
    assert isinstance(assembled, dict)
    for part, entry in parts.items():
        poses = entry["track"]["poses"]
        assert _distance(poses[-1], assembled[part]) < 1e-3, part
    broken, spare = parts["light_bulb"]["track"]["poses"], parts["light_bulb" + SPARE]["track"]["poses"]
    assert _distance(broken[0], broken[-1]) > 0.05  # taken off the lamp and set down on the table
    assert _distance(spare[0], spare[-1]) > 0.05  # fetched from the table and screwed in
    assert _distance(spare[-1], broken[0]) < 0.003  # where the broken bulb sat


def test_driven_by_its_motors_the_panda_replaces_the_bulb_and_the_lamp_lights(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    run = robot_episode(lamp, troubleshooting_task(lamp).episode("oracle", "light_bulb"), motors=True)
    driven = run.motors
    assert driven is not None and driven.failure is None, run.as_dict()
    assert driven.produces_goal and run.produces_goal
    assert [requirement.met for requirement in driven.requirements] == [True]  # the spare bulb, screwed in
    assert driven.joint_error <= TRACKING_TOLERANCE_RAD and driven.gripper_error_mm <= TRACKING_TOLERANCE_MM
    # The shade off and on, the broken bulb out, the spare in: each held without slipping.
    assert set(driven.slip_mm) == {"shade", "light_bulb"}
    assert all(slip <= SLIP_TOLERANCE_MM for slip in driven.slip_mm.values())
    assert run.as_dict()["motors"] == driven.as_dict()


def test_driven_by_its_motors_a_broken_part_never_replaced_still_gives_no_goal(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    run = robot_episode(lamp, SPARE_SHADE_ONLY, motors=True)
    driven = run.motors
    assert driven is not None and driven.failure is None, run.as_dict()
    assert all(requirement.met for requirement in driven.requirements)  # the lamp is whole, the bulb broken
    assert not driven.produces_goal and not run.produces_goal


def test_each_test_in_physics_shows_what_the_episode_observed(catalog: Catalog) -> None:
    # A spare shade first: the lamp is whole and its mechanism works, but the bulb is still broken.
    lamp = catalog.get("desk_lamp")
    steps = (
        Step("detach", "shade"),
        Step("replace", "shade"),
        Step("attach", "shade"),
        Step("test", None, "no goal"),
        Step("detach", "shade"),
        Step("detach", "light_bulb"),
        Step("replace", "light_bulb"),
        Step("attach", "light_bulb"),
        Step("attach", "shade"),
        Step("test", None, "goal"),
    )
    run = robot_episode(lamp, Episode("light_bulb", steps))
    assert [a.observed for a in run.actions if a.kind == "test"] == ["no goal", "goal"]
    assert run.produces_goal


def test_a_broken_part_never_replaced_gives_no_goal_though_the_robot_carries_it_out(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    run = robot_episode(lamp, SPARE_SHADE_ONLY)
    assert run.carried_out and run.mechanism_works and not run.produces_goal


def test_the_robot_cannot_put_the_shade_back_before_the_bulb(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    run = robot_episode(lamp, SHADE_BEFORE_BULB)
    failed = run.failed
    assert failed is not None and failed.kind == "attach" and failed.part == "light_bulb"
    assert failed.failure == "blocked_path" and not run.produces_goal


@pytest.mark.slow
def test_the_robot_lifts_the_chimney_to_light_the_lamp_and_puts_it_back(catalog: Catalog) -> None:
    lamp = catalog.get("kerosene_lamp")
    run = robot_episode(lamp, troubleshooting_task(lamp).episode("oracle", "wick"))
    assert run.produces_goal, run.as_dict()
    test = run.actions[-1]
    assert test.kind == "test" and "ignite" in test.motions


@pytest.mark.slow
def test_every_episode_of_every_strategy_is_carried_out_by_the_robot_to_the_goal(catalog: Catalog) -> None:
    carried_out = 0
    for obj in catalog.objects.values():
        task = troubleshooting_task(obj)
        done: set[tuple[Step, ...]] = set()
        for strategy in task.strategies:
            for fault in obj.faults:
                episode = task.episode(strategy, fault.part)
                if episode.steps in done:
                    continue
                done.add(episode.steps)
                run = robot_episode(obj, episode)
                where = (obj.id, strategy, fault.part)
                assert run.commands is not None and violations(run.commands) == [], where
                assert run.failed is None, (*where, run.failed)
                assert run.produces_goal, (*where, run.as_dict())
                observed = [step.observed for step in episode.steps if step.kind == "test"]
                assert [a.observed for a in run.actions if a.kind == "test"] == observed, where
                carried_out += 1
    assert carried_out == 46  # the distinct episodes of the uniform and oracle strategies on the catalog


def test_the_hand_lifts_off_the_globe_to_reach_the_valve_knob_and_puts_it_back(catalog: Catalog) -> None:
    # With the globe on, the hand above the knob touches it: the robot lifts the globe off
    # first, unscrews the knob, and puts the globe back; it does the same to screw the spare in.
    lantern = catalog.get("gas_lantern")
    run = robot_episode(lantern, troubleshooting_task(lantern).episode("uniform", "valve_knob"))
    assert run.produces_goal, run.as_dict()
    assert [(action.kind, action.part) for action in run.actions][1:4] == [
        ("detach", "valve_knob"),
        ("replace", "valve_knob"),
        ("attach", "valve_knob"),
    ]
    for action in run.actions[1], run.actions[3]:
        motions = action.motions
        assert motions[:3] == ("transit", "grasp", "push")  # the globe, lifted off its gallery
        assert "screw" in motions and motions[-3:] == ("push", "release", "retreat")  # and put back
    assert math.dist(run.placed["glass_globe"].position, run.placed["burner"].position) < 0.05  # on the burner


def test_the_panda_carries_the_broken_base_aside_and_the_spare_base_to_where_it_stood(catalog: Catalog) -> None:
    flashlight = catalog.get("flashlight")
    episode = troubleshooting_task(flashlight).episode("oracle", "case")
    run = robot_episode(flashlight, episode, tracks=True)
    assert run.produces_goal, run.as_dict()
    number = next(action.number for action in run.actions if action.kind == "replace" and action.part == "case")
    motions = run.actions[number - 1].motions
    assert motions == ("transit", "grasp", "carry", "release", "retreat") * 2  # the broken case off, the spare on
    assert run.commands is not None and violations(run.commands) == []
    document = episode_playback(flashlight, run)
    parts = {part["id"]: part for part in document["parts"]}  # type: ignore[attr-defined]
    broken, spare = parts["case"]["track"]["poses"], parts["case" + SPARE]["track"]["poses"]
    assert _distance(spare[-1], broken[0]) < 0.003  # the spare stands where the broken case stood
    assert _distance(broken[-1], broken[0]) > 0.2  # and the broken one was carried to the table


def test_the_cli_s_motors_need_the_robot() -> None:
    result = CliRunner().invoke(app, ["troubleshoot", str(LAMP), "--fault", "light_bulb", "--motors"])
    assert result.exit_code == 2 and "--motors needs --robot" in result.output


@pytest.mark.slow
def test_the_cli_drives_the_panda_s_episode_by_its_motors() -> None:
    args = ["troubleshoot", str(LAMP), "--fault", "light_bulb", "--strategy", "oracle", "--robot", "--motors"]
    result = CliRunner().invoke(app, [*args, "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    motors = data["robot"]["motors"]
    assert data["status"] == "repaired" and motors["produces_goal"] and motors["failure"] is None
    assert motors["tracking"]["max_joint_error_rad"] <= motors["tracking"]["tolerance_rad"]
    said = CliRunner().invoke(app, args)
    assert said.exit_code == 0 and "Driven by its motors: gives light" in said.output, said.output


@pytest.mark.slow
def test_the_cli_has_the_panda_carry_out_the_episode_and_check_trajectory_passes_it(tmp_path: Path) -> None:
    out = tmp_path / "repair.json"
    args = ["troubleshoot", str(LAMP), "--fault", "light_bulb", "--robot", "--trajectory", str(out), "--json"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    assert data["status"] == "repaired" and data["robot"]["produces_goal"]
    assert [a["action"] for a in data["robot"]["actions"]] == [a["action"] for a in data["steps"]]
    checked = CliRunner().invoke(app, ["check-trajectory", str(out), "--json"])
    assert checked.exit_code == 0, checked.output
    assert json.loads(checked.output)["violations"] == []
