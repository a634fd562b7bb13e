"""Time parameterization: the robot's planned paths made into motor commands within its limits.

Each segment's path (its waypoints, from where the previous one ended) is parameterized by
TOPP-RA (``toppra``: time-optimal under the joint velocity and acceleration limits times a
safety factor), starting and ending at rest, so consecutive segments join with matching
position and velocity. A gripper-only segment (grasp, release) takes the time the fingers
need at the gripper's speed times the same factor. The result is sampled ``COMMAND_RATE_HZ``
times a second and checked by the independent checker (``sim.robot.checker``, against the
datasheet); a segment that breaks a limit (jerk included: TOPP-RA bounds acceleration, not
its rate of change) is parameterized again with a smaller factor, up to ``RETRIES`` times.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

from causalplan.errors import CausalPlanError
from causalplan.sim.robot.checker import violations
from causalplan.sim.robot.limits import RobotLimits
from causalplan.sim.robot.panda import Configuration
from causalplan.sim.robot.trajectory import Point, Segment, TimedSegment, Trajectory, Waypoints

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

COMMAND_RATE_HZ = 100
"""Motor commands a second in a trajectory (a real controller interpolates between them)."""
RETRIES = 6
SLOWER = 0.7
"""How much smaller the safety factor gets for a segment that broke a limit."""
SAME = 1e-9
"""Radians under which two waypoints are the same."""


class LimitViolationError(CausalPlanError):
    """No time parameterization of a path keeps within the robot's limits."""

    code = "limit_violation"


def _rest(position: Configuration, width: float, time: float) -> Point:
    zeros = (0.0,) * len(position)
    return Point(time, position, zeros, zeros, width)


def _arm_points(
    path: NDArray[np.float64], limits: RobotLimits, factor: float, width: float, start: float
) -> list[Point]:
    """Return the points (after the first) of a path parameterized by TOPP-RA, from rest to rest."""
    import numpy as np
    import toppra
    import toppra.algorithm
    import toppra.constraint

    logging.getLogger("toppra").setLevel(logging.WARNING)
    velocity, acceleration, _ = limits.scaled(factor)
    ss = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    spline = toppra.SplineInterpolator(ss, path)
    constraints = [
        toppra.constraint.JointVelocityConstraint(np.array([[-v, v] for v in velocity])),
        toppra.constraint.JointAccelerationConstraint(np.array([[-a, a] for a in acceleration])),
    ]
    instance = toppra.algorithm.TOPPRA(constraints, spline, parametrizer="ParametrizeConstAccel")
    timed = instance.compute_trajectory(0.0, 0.0)
    if timed is None:
        raise LimitViolationError("TOPP-RA found no parameterization of a path within the robot's limits.")
    count = max(2, math.ceil(timed.duration * COMMAND_RATE_HZ))
    times = np.linspace(0.0, timed.duration, count + 1)
    q, dq, ddq = timed(times), timed(times, 1), timed(times, 2)
    dq[-1], ddq[-1] = 0.0, 0.0  # at rest at the end, exactly
    q[-1] = path[-1]
    return [
        Point(start + float(t), tuple(map(float, q[k])), tuple(map(float, dq[k])), tuple(map(float, ddq[k])), width)
        for k, t in enumerate(times)
        if k > 0
    ]


def _gripper_points(
    position: Configuration, width: tuple[float, float], limits: RobotLimits, factor: float, start: float
) -> list[Point]:
    """Return the points (after the first) of the fingers moving from one width to another, the arm at rest."""
    seconds = abs(width[1] - width[0]) / (limits.gripper_speed * factor)
    count = max(2, math.ceil(seconds * COMMAND_RATE_HZ))
    return [
        _rest(position, width[0] + (width[1] - width[0]) * k / count, start + seconds * k / count)
        for k in range(1, count + 1)
    ]


def _segment_points(segment: Segment, last: Point, limits: RobotLimits, factor: float) -> list[Point]:
    import numpy as np

    path = [last.positions]
    for position in segment.positions:
        if max(abs(a - b) for a, b in zip(position, path[-1], strict=True)) > SAME:
            path.append(position)
    if len(path) == 1:
        return _gripper_points(last.positions, (last.gripper_width, segment.width), limits, factor, last.time)
    return _arm_points(np.array(path), limits, factor, segment.width, last.time)


def _within(points: list[Point], limits: RobotLimits) -> bool:
    return not violations(Trajectory(limits, 1.0, tuple(points)), limits)


def time_parameterize(
    waypoints: Waypoints, start: Configuration, width: float, limits: RobotLimits, safety_factor: float
) -> Trajectory:
    """Return the motor commands for ``waypoints`` from rest at ``start`` (gripper ``width`` metres open).

    Raises LimitViolationError when a segment cannot be kept within the datasheet's limits.
    """
    if not 0.0 < safety_factor <= 1.0:
        raise LimitViolationError(f"The safety factor must be above 0 and at most 1, not {safety_factor}.")
    points = [_rest(start, width, 0.0)]
    segments: list[TimedSegment] = []
    for segment in waypoints.segments:
        if not segment.positions:
            continue
        last, factor = points[-1], safety_factor
        for _ in range(RETRIES):
            added = _segment_points(segment, last, limits, factor)
            # The segment, and its join with the previous one: jerk spans three points back.
            if _within([*points[-3:], *added], limits):
                break
            factor *= SLOWER
        else:
            detail = f"step {segment.step}, {segment.kind}"
            raise LimitViolationError(f"No parameterization of the robot's path keeps within its limits ({detail}).")
        segments.append(
            TimedSegment(segment.step, segment.kind, segment.gripper, len(points) - 1, len(points) - 1 + len(added))
        )
        points.extend(added)
    return Trajectory(limits, safety_factor, tuple(points), tuple(segments))
