"""The browser player's document: motor commands, parts' shapes and tracks that end where the run let go."""

from __future__ import annotations

import bisect
import json

import pytest

from causalplan.sim import RenderMode, simulate_plan
from causalplan.sim.poses import Pose, difference
from causalplan.sim.robot.playback import FORMAT, NoMotorCommandsError, playback
from causalplan.sim.robot.replay import part_tracks
from causalplan.sim.robot.tracks import PartTrack
from tests.conftest import builtin_catalog
from tests.sim.fixtures import CORRECT_PLANS


@pytest.mark.slow
def test_every_part_track_starts_at_rest_and_ends_where_the_robot_let_it_go() -> None:
    obj = builtin_catalog().get("desk_lamp")
    report = simulate_plan(obj, CORRECT_PLANS["desk_lamp"], render=RenderMode.NONE, robot=True, tracks=True)
    document = json.loads(json.dumps(playback(obj, CORRECT_PLANS["desk_lamp"], report)))
    assert document["format"] == FORMAT and document["object"] == "desk_lamp"
    commands = document["trajectory"]
    assert commands["times"][-1] == document["seconds"] > 0
    assert len(commands["times"]) == len(commands["positions"]) == len(commands["gripper_widths"])
    assert report.motor_commands is not None and len(commands["times"]) == len(report.motor_commands.points)
    assert commands["times"] == sorted(set(commands["times"]))  # rounded, every command still has its own time
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


@pytest.mark.slow
def test_the_tracks_the_run_records_are_those_its_motor_commands_replay_to_in_a_fresh_scene() -> None:
    """The run keeps the parts' poses as it goes (no second scene); a replay of its commands agrees."""
    catalog = builtin_catalog()
    for object_id in ("flashlight", "candle"):
        obj = catalog.get(object_id)
        steps = CORRECT_PLANS[object_id]
        report = simulate_plan(obj, steps, render=RenderMode.NONE, robot=True, tracks=True)
        assert report.motor_commands is not None and set(report.tracks) == {part.id for part in obj.parts}
        replayed = part_tracks(obj, steps, report.motor_commands)
        for part, track in report.tracks.items():
            again = replayed[part]
            assert track.released == again.released and track.times[0] == 0.0, part
            for time, pose in zip(track.times, track.poses, strict=True):
                (moved, turned) = difference(pose, _pose_at(again, time))
                assert moved < 1e-4 and turned < 1e-3, (object_id, part, time)
        document = playback(obj, steps, report)
        played = {part["id"]: part["track"]["times"] for part in document["parts"]}  # type: ignore[attr-defined]
        assert played == {part: [round(t, 4) for t in track.times] for part, track in report.tracks.items()}


def _pose_at(track: PartTrack, time: float) -> Pose:
    """Return the track's pose at ``time``: its last keyframe at or before it."""
    return track.poses[max(0, bisect.bisect_right(track.times, time) - 1)]


@pytest.mark.slow
def test_a_run_not_asked_for_tracks_keeps_none_and_its_playback_replays_them() -> None:
    obj = builtin_catalog().get("candle")
    report = simulate_plan(obj, CORRECT_PLANS["candle"], render=RenderMode.NONE, robot=True)
    assert report.tracks == {} and report.motor_commands is not None
    document = playback(obj, CORRECT_PLANS["candle"], report)
    (wick,) = [part for part in document["parts"] if part["id"] == "wick"]  # type: ignore[attr-defined]
    assert wick["track"]["poses"][-1] == document["assembled"]["wick"]  # type: ignore[index]
