"""Time parameterization: planned waypoints made into motor commands within the Panda's limits."""

from __future__ import annotations

import pytest

from causalplan.sim.robot.checker import violations
from causalplan.sim.robot.limits import PANDA
from causalplan.sim.robot.timing import LimitViolationError, time_parameterize
from causalplan.sim.robot.trajectory import Segment, Waypoints

HOME = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)
TURNED = (*HOME[:6], HOME[6] + 1.5)


def plan() -> Waypoints:
    return Waypoints(
        [
            Segment(1, "transit", "open", 0.08, [TURNED]),  # one big jump: the parameterization makes it a motion
            Segment(1, "grasp", "closed", 0.03, [TURNED] * 20),
            Segment(1, "transit", "closed", 0.03, [HOME]),
        ]
    )


def test_segments_join_at_rest_within_the_limits() -> None:
    trajectory = time_parameterize(plan(), HOME, 0.08, PANDA, 0.5)
    assert violations(trajectory) == []
    assert [segment.kind for segment in trajectory.segments] == ["transit", "grasp", "transit"]
    for segment in trajectory.segments:
        first, last = trajectory.points[segment.first], trajectory.points[segment.last]
        assert max(map(abs, first.velocities)) == 0.0 and max(map(abs, last.velocities)) == 0.0
    assert trajectory.points[trajectory.segments[0].last].positions == pytest.approx(TURNED)
    grasp = trajectory.segments[1]
    assert trajectory.points[grasp.last].gripper_width == pytest.approx(0.03)
    assert trajectory.points[-1].positions == pytest.approx(HOME)


def test_a_smaller_safety_factor_takes_longer_and_moves_slower() -> None:
    fast = time_parameterize(plan(), HOME, 0.08, PANDA, 0.5)
    slow = time_parameterize(plan(), HOME, 0.08, PANDA, 0.25)
    assert slow.seconds > 1.5 * fast.seconds
    top = max(abs(point.velocities[6]) for point in slow.points)
    assert top <= 0.25 * PANDA.velocity[6] * 1.01


def test_a_safety_factor_outside_0_to_1_is_refused() -> None:
    with pytest.raises(LimitViolationError) as raised:
        time_parameterize(plan(), HOME, 0.08, PANDA, 1.5)
    assert raised.value.code == "limit_violation"
