"""The robot's share of one plan step: bring the part to its approach, drive it home, let go.

The executor (``sim.executor``) keeps its physics checks; around them these functions make
the robot do the motions: before the approach, ``bring`` (transit, grasp, carry); after the
simulator's approach found how far the part gets, ``drive`` (the straight line along the
connector axis, split into approach and the primitive: screw, push or ignite); once the
joint is made, ``let_go`` (release and retreat, or for a flame, carry it back to the table).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from causalplan.objects.model import Part
from causalplan.sim.motions import ENGAGEMENT, Motion
from causalplan.sim.outcomes import RobotFailure
from causalplan.sim.poses import Pose
from causalplan.sim.robot.robot import LIFT, LINE_STEP, SCREW_STEP, Robot, line_poses
from causalplan.sim.robot.trajectory import Waypoints

PUSH_DEPTH = 0.005
"""Metres of the approach, at its end, that are the push home (insert, clip, place) or the touch (ignite)."""
SCREW_START_POSES = 9
"""Poses of a screw's turn (10 degrees each) that choose the arm pose it is brought or grasped with."""


def bring(
    robot: Robot, part_id: str, part: Part, motion: Motion, path: Callable[[float], Pose], start: float, mate: str
) -> RobotFailure | None:
    """Fetch the part from the table and carry it to the start of its approach."""
    failure = robot.fetch(part_id, part)
    if failure is None:
        end = min(start, ENGAGEMENT) if motion.turns > 0 else 0.0
        line = [path(d) for d in spaced_distances(start, end, LINE_STEP)]
        if motion.turns > 0:
            # The arm pose must also turn the screw's first quarter: one that starts the turn
            # with a joint at its limit cannot go on (the wrist alone regrasps).
            turn = spaced_distances(end, 0.0, screw_spacing(motion))[:SCREW_START_POSES]
            line += [path(d) for d in turn]
        failure = robot.carry(path(start), f"at the approach of the {part.name}", line, mate)
    return failure


def spaced_distances(start: float, end: float, step: float) -> list[float]:
    """Return the distances from ``start`` (left out) to ``end`` (kept), evenly spaced at most ``step`` apart."""
    count = max(1, math.ceil(abs(start - end) / step))
    return [start + (end - start) * k / count for k in range(1, count + 1)]


def screw_spacing(motion: Motion) -> float:
    """Return the metres between a screw's poses along its thread: a line's step, or less for the turn's step."""
    spin_per_metre = 2 * math.pi * motion.turns / ENGAGEMENT
    return min(LINE_STEP, SCREW_STEP / spin_per_metre)


def drive(
    robot: Robot, motion: Motion, path: Callable[[float], Pose], start: float, stopped: float, name: str, mate: str
) -> RobotFailure | None:
    """Move the held part from ``start`` to ``stopped`` (metres from the seat) along its path, by the primitive."""
    what = f"driving the {name} home"
    if motion.turns > 0:
        thread = max(stopped, min(start, ENGAGEMENT))
        failure = robot.follow("approach", [path(d) for d in spaced_distances(start, thread, LINE_STEP)], what, mate)
        if failure is not None or thread <= stopped:
            return failure
        return robot.screw([path(d) for d in spaced_distances(thread, stopped, screw_spacing(motion))], what, mate)
    push = max(stopped, min(start, PUSH_DEPTH))
    failure = robot.follow("approach", [path(d) for d in spaced_distances(start, push, LINE_STEP)], what, mate)
    if failure is not None or push <= stopped:
        return failure
    kind = "ignite" if motion.touches_only else "push"
    return robot.follow(kind, [path(d) for d in spaced_distances(push, stopped, LINE_STEP)], what, mate)


def let_go(
    robot: Robot, motion: Motion, path: Callable[[float], Pose], start: float, home: Pose, name: str, mate: str
) -> RobotFailure | None:
    """Release the joined part and retreat; a flame first goes back along its line and to its place on the table."""
    if motion.touches_only:
        back = robot.follow(
            "ignite", [path(d) for d in spaced_distances(0.0, start, LINE_STEP)], f"taking the {name} back", mate
        )
        if back is not None:
            return back
        above = home.translated((0.0, 0.0, LIFT))
        failure = robot.carry(above, f"taking the {name} back to the table")
        if failure is not None:
            return failure
        assert robot.held is not None
        failure = robot.follow(
            "carry", [pose for pose in line_poses(above, home)], f"putting the {name} down", "ground"
        )
        if failure is not None:
            return failure
    return robot.release(mate=None if motion.touches_only else mate)


def step_motions(waypoints: Waypoints, step: int) -> tuple[str, ...]:
    """Return the kinds of motion the robot made in ``step``, in order, repeats merged."""
    kinds: list[str] = []
    for segment in waypoints.segments:
        if segment.step == step and segment.positions and (not kinds or kinds[-1] != segment.kind):
            kinds.append(segment.kind)
    return tuple(kinds)
