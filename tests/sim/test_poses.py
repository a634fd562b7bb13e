"""Rigid poses and quaternions, checked against small known answers."""

from __future__ import annotations

import math

import pytest

from causalplan.sim.poses import (
    Pose,
    about_axis,
    angle_between,
    difference,
    from_rpy,
    rotate,
    rotation_angle,
    shortest_arc,
)

X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)


def close(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    return all(math.isclose(x, y, abs_tol=1e-9) for x, y in zip(a, b, strict=True))


def test_a_quarter_turn_about_z_takes_x_to_y() -> None:
    assert close(rotate(about_axis(Z, math.pi / 2), X), Y)


def test_roll_pitch_yaw_compose_like_pybullet() -> None:
    # Yaw 90 degrees after pitch 90 degrees: x goes down (pitch), then stays down.
    assert close(rotate(from_rpy((0.0, math.pi / 2, 0.0)), X), (0.0, 0.0, -1.0))
    assert close(rotate(from_rpy((0.0, 0.0, math.pi / 2)), X), Y)


@pytest.mark.parametrize("source", [X, Y, Z, (0.0, 0.0, -1.0), (0.6, 0.0, 0.8)])
@pytest.mark.parametrize("target", [X, (-1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, 0.8, 0.6)])
def test_shortest_arc_turns_one_direction_onto_another(
    source: tuple[float, float, float], target: tuple[float, float, float]
) -> None:
    turn = shortest_arc(source, target)
    assert close(rotate(turn, source), target)
    assert rotation_angle(turn) == pytest.approx(angle_between(source, target), abs=1e-9)


def test_a_pose_and_its_inverse_cancel() -> None:
    pose = Pose((0.1, -0.2, 0.3), about_axis(Y, 0.7))
    identity = pose * pose.inverse()
    assert close(identity.position, (0.0, 0.0, 0.0))
    assert rotation_angle(identity.orientation) == pytest.approx(0.0, abs=1e-9)
    assert close((pose.inverse() * pose).apply((1.0, 2.0, 3.0)), (1.0, 2.0, 3.0))


def test_difference_gives_distance_and_angle() -> None:
    moved, turned = difference(Pose(), Pose((0.003, 0.004, 0.0), about_axis(Z, 0.1)))
    assert moved == pytest.approx(0.005)
    assert turned == pytest.approx(0.1)
