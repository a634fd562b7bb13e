"""The plan's primitives as motions: approach along the connector axis, turning for a screw.

Every primitive moves the part from outside the assembly's bounds straight down the fixed
connector's axis to its seat, checking for overlaps on the way (``approach``). What happens
at the seat depends on the primitive: most fasten (a weld where the part actually is),
``place`` lets the part rest under gravity, and ``ignite`` touches and goes back.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from causalplan.objects.model import Vector
from causalplan.sim.checks import PENETRATION_TOLERANCE_MM
from causalplan.sim.geometry import Box, Frame, bounding_box, mating_pose
from causalplan.sim.poses import Pose, add, scale
from causalplan.sim.scene import Scene


@dataclass(frozen=True)
class Motion:
    """How a primitive moves its part: turns on the way in, and what happens at the seat."""

    turns: float = 0.0
    fastens: bool = True  # welded where it ends up
    touches_only: bool = False  # goes back after touching (lighting a wick)


MOTIONS: dict[str, Motion] = {
    "screw": Motion(turns=2.0),
    "insert": Motion(),
    "connect": Motion(),
    "clip": Motion(),
    "plug": Motion(),
    "place": Motion(fastens=False),
    "ignite": Motion(fastens=False, touches_only=True),
}
"""Every primitive of the catalog (``PRIMITIVE_TEXTS``) with its motion."""

SWEEP_STEP = 0.002
"""Metres between two checked poses of an approach."""
ENGAGEMENT = 0.015
"""A screw turns over the last this-many metres of its approach (the thread)."""
APPROACH_MARGIN = 0.02
MIN_APPROACH = 0.03
MAX_APPROACH = 1.0
_BISECTIONS = 10


def clearance(moving: Box, obstacle: Box, direction: Vector) -> float:
    """Return how far ``moving`` must travel along the unit ``direction`` to clear ``obstacle`` (>= 0)."""
    if any(moving[1][i] <= obstacle[0][i] or moving[0][i] >= obstacle[1][i] for i in range(3)):
        return 0.0
    distances = []
    for i in range(3):
        if direction[i] > 1e-9:
            distances.append((obstacle[1][i] - moving[0][i]) / direction[i])
        elif direction[i] < -1e-9:
            distances.append((obstacle[0][i] - moving[1][i]) / direction[i])
    return max(0.0, min(distances))


def approach_start(moving: Box, obstacle: Box, direction: Vector) -> float:
    """Return where an approach begins: clear of the assembly's bounds, plus a margin."""
    return min(MAX_APPROACH, max(MIN_APPROACH, clearance(moving, obstacle, direction) + APPROACH_MARGIN))


def approach_path(fixed_pose: Pose, moving: Frame, fixed: Frame, motion: Motion) -> Callable[[float], Pose]:
    """Return the moving part's world pose as a function of its distance (metres) from the seat."""
    direction = fixed_pose.turn(fixed.axis)

    def pose_at(distance: float) -> Pose:
        spin = -2 * math.pi * motion.turns * min(distance, ENGAGEMENT) / ENGAGEMENT
        return (fixed_pose * mating_pose(moving, fixed, spin)).translated(scale(direction, distance))

    return pose_at


@dataclass(frozen=True)
class Approach:
    """How an approach went: where it began and stopped (metres from the seat) and what it hit."""

    start: float
    stopped: float
    clear_depth: float  # the deepest overlap (metres) among the poses it passed through
    hit_depth: float  # the overlap (metres) at the pose that stopped it; 0 when it reached its seat
    hit: str | None  # what stopped the part (a part id, or "ground"); None when it reached its seat


def approach(scene: Scene, part_id: str, path: Callable[[float], Pose], start: float) -> Approach:
    """Move a part along ``path`` from ``start`` to its seat, stopping at the first overlap too deep.

    Poses are checked every ``SWEEP_STEP``; when one overlaps something by more than the
    tolerance, the last clear distance is refined by bisection and the part is left there.
    """
    tolerance = PENETRATION_TOLERANCE_MM / 1000
    solid = scene.solids[part_id]
    reach = solid.radius + SWEEP_STEP
    lower, upper = bounding_box([path(start).apply(solid.center), path(0.0).apply(solid.center)])
    near = scene.bodies_near(add(lower, (-reach, -reach, -reach)), add(upper, (reach, reach, reach)))
    # Only parts and the table count: not the robot arm, not drawn lights, not the part itself.
    candidates = {body for body in near if body in scene.names and body != scene.bodies[part_id]}
    count = max(1, math.ceil(start / SWEEP_STEP))
    worst, clear = 0.0, start
    for index in range(count + 1):
        distance = start * (1 - index / count)
        scene.place(part_id, path(distance))
        depth, hit = scene.deepest_overlap(part_id, candidates)
        if depth > tolerance:
            stopped = _last_clear(scene, part_id, path, candidates, clear, distance, tolerance)
            scene.place(part_id, path(stopped))
            return Approach(start, stopped, worst, depth, hit)
        worst, clear = max(worst, depth), distance
    return Approach(start, 0.0, worst, 0.0, None)


def _last_clear(
    scene: Scene,
    part_id: str,
    path: Callable[[float], Pose],
    candidates: set[int],
    clear: float,
    blocked: float,
    tolerance: float,
) -> float:
    """Return the distance nearest the seat between ``clear`` and ``blocked`` where nothing overlaps too deep."""
    for _ in range(_BISECTIONS):
        middle = (clear + blocked) / 2
        scene.place(part_id, path(middle))
        if scene.deepest_overlap(part_id, candidates)[0] > tolerance:
            blocked = middle
        else:
            clear = middle
    return clear
