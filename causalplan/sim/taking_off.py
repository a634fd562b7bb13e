"""Taking a part off an object in the scene: where it sits along its approach, its weld undone."""

from __future__ import annotations

import math
from collections.abc import Callable

from causalplan.sim.poses import Pose, difference
from causalplan.sim.scene import Scene

ALONG_STEP = 0.0001
"""Metres between the distances tried when finding where a part sits along its approach."""
ALONG_METRES_PER_RADIAN = 0.01
"""How a turn counts against a shift when matching a part's pose to its approach (1 cm a radian)."""


def along(path: Callable[[float], Pose], pose: Pose, start: float) -> float:
    """Return how far (metres) along its approach ``path`` a part at ``pose`` sits from its seat.

    A part can stop short of its seat (within the fit's tolerance); a screw stopped 1 mm
    short is turned some 50 degrees back from the seat's angle, so its way out starts there.
    """
    count = max(1, math.ceil(start / ALONG_STEP))
    distances = [start * k / count for k in range(count + 1)]
    return min(distances, key=lambda d: _mismatch(path(d), pose))


def _mismatch(a: Pose, b: Pose) -> float:
    metres, radians = difference(a, b)
    return metres + radians * ALONG_METRES_PER_RADIAN


def unweld(scene: Scene, fixed: str, moving: str) -> None:
    """Undo the weld between two parts (if any) and let them collide again."""
    pb, client = scene.pb, scene.client
    pair = {scene.bodies[fixed], scene.bodies[moving]}
    for index in range(pb.getNumConstraints(physicsClientId=client)):
        constraint = pb.getConstraintUniqueId(index, physicsClientId=client)
        info = pb.getConstraintInfo(constraint, physicsClientId=client)
        if {info[0], info[2]} == pair:
            pb.removeConstraint(constraint, physicsClientId=client)
            break


def collide_again(scene: Scene, a: str, b: str) -> None:
    pb, client = scene.pb, scene.client
    body_a, body_b = scene.bodies[a], scene.bodies[b]
    for link_a in range(-1, pb.getNumJoints(body_a, physicsClientId=client)):
        for link_b in range(-1, pb.getNumJoints(body_b, physicsClientId=client)):
            pb.setCollisionFilterPair(body_a, body_b, link_a, link_b, 1, physicsClientId=client)
