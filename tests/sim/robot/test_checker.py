"""The independent checker: velocity, acceleration and jerk recomputed from positions and times."""

from __future__ import annotations

import math

import pytest

from causalplan.sim.robot.checker import violations
from causalplan.sim.robot.limits import PANDA
from causalplan.sim.robot.trajectory import Point, Trajectory

HOME = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)
ZEROS = (0.0,) * 7


def moving_joint(joint: int, angles: list[float], step: float = 0.01, width: float = 0.08) -> Trajectory:
    """Return a trajectory that moves one joint through ``angles``, one every ``step`` seconds."""
    points = []
    for k, angle in enumerate(angles):
        position = tuple(angle if i == joint else value for i, value in enumerate(HOME))
        points.append(Point(k * step, position, ZEROS, ZEROS, width))
    return Trajectory(PANDA, 1.0, tuple(points))


def test_a_slow_smooth_motion_is_within_the_limits() -> None:
    angles = [0.785 + 0.5 * (1 - math.cos(k / 100 * math.pi)) for k in range(101)]
    assert violations(moving_joint(6, angles, step=0.02)) == []


def test_joint_7_twice_too_fast_is_refused_with_the_joint_the_time_and_the_ratio() -> None:
    # 0.0522 rad every 10 ms is 5.22 rad/s: twice joint 7's 2.61 rad/s.
    found = [v for v in violations(moving_joint(6, [0.785 + 0.0522 * k for k in range(5)])) if v.quantity == "velocity"]
    assert {v.joint for v in found} == {"panda_joint7"}
    assert found[0].time == pytest.approx(0.005)
    assert found[0].ratio == pytest.approx(2.0, rel=1e-3)
    assert found[0].limit == 2.61


def test_a_jump_between_two_points_breaks_acceleration_and_jerk_too() -> None:
    found = violations(moving_joint(1, [-0.785, -0.785, -0.6, -0.6]))
    assert {v.quantity for v in found} >= {"velocity", "acceleration", "jerk"}
    assert {v.joint for v in found} == {"panda_joint2"}


def test_a_position_beyond_the_datasheet_is_refused_though_the_urdf_allows_it() -> None:
    found = violations(moving_joint(6, [2.9, 2.9, 2.9], step=1.0))
    assert {(v.quantity, v.joint) for v in found} == {("position", "panda_joint7")}
    assert found[0].limit == 2.8973 and found[0].ratio > 1


def test_a_gripper_wider_than_the_hand_opens_is_refused() -> None:
    found = violations(moving_joint(0, [0.0, 0.0], step=1.0, width=0.1))
    assert {v.quantity for v in found} == {"gripper_width"}
