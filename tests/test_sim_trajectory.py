"""Reading a robot trajectory file: the documented shape, and clear errors for anything else."""

from __future__ import annotations

import pytest

from causalplan.sim.robot.panda import JOINT_NAMES
from causalplan.sim.robot.trajectory import Segment, Trajectory, TrajectoryInputError, read_trajectory

HOME = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]


def good() -> dict[str, object]:
    return {
        "robot": "franka_panda",
        "joints": list(JOINT_NAMES),
        "rate_hz": 50,
        "segments": [{"step": 1, "kind": "transit", "gripper": "open", "positions": [HOME, HOME]}],
    }


def test_a_trajectory_reads_back_what_was_written() -> None:
    written = Trajectory(
        [Segment(1, "transit", "open", [tuple(HOME)] * 2), Segment(1, "grasp", "closed", [tuple(HOME)])]
    )
    again = read_trajectory(written.as_dict())
    assert again.as_dict() == written.as_dict()
    assert again.seconds == pytest.approx(3 / 50)


@pytest.mark.parametrize(
    ("change", "says"),
    [
        ({"robot": "kuka_iiwa"}, "not for the franka_panda"),
        ({"rate_hz": 0}, "'rate_hz' must be a whole number"),
        ({"rate_hz": True}, "'rate_hz' must be a whole number"),
        ({"segments": {}}, "'segments' must be a list"),
        ({"segments": [{"step": 1, "kind": "dance", "gripper": "open", "positions": [HOME]}]}, "unknown kind 'dance'"),
        ({"segments": [{"step": 0, "kind": "grasp", "gripper": "open", "positions": [HOME]}]}, "'step' must be"),
        ({"segments": [{"step": 1, "kind": "grasp", "gripper": "ajar", "positions": [HOME]}]}, "'open' or 'closed'"),
        ({"segments": [{"step": 1, "kind": "grasp", "gripper": "open", "positions": []}]}, "non-empty list"),
        ({"segments": [{"step": 1, "kind": "grasp", "gripper": "open", "positions": [HOME[:6]]}]}, "list of 7"),
        (
            {"segments": [{"step": 1, "kind": "grasp", "gripper": "open", "positions": [[*HOME[:6], float("nan")]]}]},
            "segment 1, position 1: joint angles must be finite numbers",
        ),
        ({"segments": [{"step": 1, "kind": "grasp", "gripper": "open"}]}, "needs exactly 'step', 'kind'"),
    ],
)
def test_a_wrong_trajectory_says_what_is_wrong_and_where(change: dict[str, object], says: str) -> None:
    with pytest.raises(TrajectoryInputError) as raised:
        read_trajectory({**good(), **change})
    assert says in raised.value.message


def test_a_trajectory_must_be_an_object() -> None:
    with pytest.raises(TrajectoryInputError):
        read_trajectory([1, 2, 3])
