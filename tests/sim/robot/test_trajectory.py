"""Reading a robot trajectory file: the documented shape, and clear errors for anything else."""

from __future__ import annotations

import pytest

from causalplan.sim.robot.limits import PANDA, UnknownRobotError
from causalplan.sim.robot.trajectory import Point, TimedSegment, Trajectory, TrajectoryInputError, read_trajectory

HOME = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)
ZEROS = (0.0,) * 7


def written() -> Trajectory:
    points = (Point(0.0, HOME, ZEROS, ZEROS, 0.08), Point(0.5, HOME, ZEROS, ZEROS, 0.03))
    return Trajectory(PANDA, 0.5, points, (TimedSegment(1, "grasp", "closed", 0, 1),))


def good() -> dict[str, object]:
    return {"joints": list(PANDA.joints), "points": [{"time_from_start": 0.0, "positions": list(HOME)}]}


def test_a_trajectory_reads_back_what_was_written() -> None:
    data = written().as_dict()
    again = read_trajectory(data)
    assert again.as_dict() == data
    assert again.seconds == pytest.approx(0.5)
    assert data["robot"] == "panda" and data["limits"]["safety_factor"] == 0.5  # type: ignore[index]
    assert data["limits"]["velocity"] == list(PANDA.velocity)  # type: ignore[index]


def test_a_users_file_needs_only_joints_times_and_positions() -> None:
    trajectory = read_trajectory(good())
    assert trajectory.limits is PANDA and trajectory.points[0].velocities == ZEROS


@pytest.mark.parametrize(
    ("change", "says"),
    [
        ({"joints": ["a"] * 7}, "'joints' must be the panda's"),
        ({"points": []}, "'points' must be a non-empty list"),
        ({"points": [{"positions": list(HOME)}]}, "point 0: needs 'time_from_start'"),
        ({"points": [{"time_from_start": 0, "positions": list(HOME[:6])}]}, "point 0: 'positions' must be a list of 7"),
        (
            {"points": [{"time_from_start": 0, "positions": [*HOME[:6], float("nan")]}]},
            "point 0: 'positions' must hold finite numbers",
        ),
        (
            {
                "points": [
                    {"time_from_start": 1, "positions": list(HOME)},
                    {"time_from_start": 1, "positions": list(HOME)},
                ]
            },
            "point 1: 'time_from_start' must grow",
        ),
        ({"segments": [{"step": 1, "kind": "dance", "gripper": "open", "first": 0, "last": 0}]}, "unknown kind"),
        ({"segments": [{"step": 1, "kind": "grasp", "gripper": "ajar", "first": 0, "last": 0}]}, "'open' or 'closed'"),
        ({"segments": [{"step": 1, "kind": "grasp", "gripper": "open", "first": 0, "last": 3}]}, "not among the 1"),
        ({"rate_hz": 50, "points": None, "segments": []}, "'points' must be a non-empty list"),
    ],
)
def test_a_wrong_trajectory_says_what_is_wrong_and_where(change: dict[str, object], says: str) -> None:
    with pytest.raises(TrajectoryInputError) as raised:
        read_trajectory({**good(), **change})
    assert raised.value.code == "invalid_trajectory"
    assert says in raised.value.message


def test_a_file_of_the_first_format_is_refused_with_what_to_do() -> None:
    old = {"robot": "franka_panda", "joints": list(PANDA.joints), "rate_hz": 50, "segments": []}
    with pytest.raises(TrajectoryInputError) as raised:
        read_trajectory(old)
    assert "first format" in raised.value.message and "--trajectory" in raised.value.message


def test_an_unknown_robot_is_refused_with_the_models_known() -> None:
    with pytest.raises(UnknownRobotError) as raised:
        read_trajectory({**good(), "robot": "kuka_iiwa"})
    assert raised.value.code == "unknown_robot" and "panda" in raised.value.message


def test_a_trajectory_must_be_an_object() -> None:
    with pytest.raises(TrajectoryInputError):
        read_trajectory([1, 2, 3])
