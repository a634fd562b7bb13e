"""The browser player's document: motor commands, parts' shapes and tracks that end where the run let go."""

from __future__ import annotations

import json

import pytest

from causalplan.sim import RenderMode, simulate_plan
from causalplan.sim.poses import Pose, difference
from causalplan.sim.robot.playback import FORMAT, NoMotorCommandsError, playback
from tests.conftest import builtin_catalog
from tests.sim_fixtures import CORRECT_PLANS


@pytest.mark.slow
def test_every_part_track_starts_at_rest_and_ends_where_the_robot_let_it_go() -> None:
    obj = builtin_catalog().get("desk_lamp")
    report = simulate_plan(obj, CORRECT_PLANS["desk_lamp"], render=RenderMode.NONE, robot=True)
    document = json.loads(json.dumps(playback(obj, CORRECT_PLANS["desk_lamp"], report)))
    assert document["format"] == FORMAT and document["object"] == "desk_lamp"
    assert document["trajectory"]["points"][-1]["time_from_start"] == document["seconds"] > 0
    parts = {part["id"]: part for part in document["parts"]}
    assert set(parts) == {"shade", "light_bulb", "base_with_cables"}
    assert set(document["assembled"]) == set(report.placed) == {"shade", "light_bulb"}
    for part_id, placed in report.placed.items():
        track = parts[part_id]["track"]
        assert track["times"][0] == 0.0 and track["times"] == sorted(set(track["times"]))
        assert len(track["poses"]) == len(track["times"]) > 2  # at rest, then carried
        last = track["poses"][-1]
        moved, turned = difference(Pose(tuple(last[:3]), tuple(last[3:])), placed)
        assert moved < 1e-4 and turned < 1e-3
        assert difference(Pose(tuple(track["poses"][0][:3]), tuple(track["poses"][0][3:])), placed)[0] > 0.05
    base = parts["base_with_cables"]
    assert len(base["track"]["poses"]) == 1  # the robot never moves the base
    assert {shape["kind"] for shape in base["shapes"]} <= {"box", "cylinder", "sphere"}


def test_a_run_without_motor_commands_has_nothing_to_play() -> None:
    obj = builtin_catalog().get("desk_lamp")
    report = simulate_plan(obj, CORRECT_PLANS["desk_lamp"], render=RenderMode.NONE)
    with pytest.raises(NoMotorCommandsError) as raised:
        playback(obj, CORRECT_PLANS["desk_lamp"], report)
    assert raised.value.code == "no_motor_commands"
