"""Where the parts start and where the plan means them to end: the table's layout and the designed poses.

The base stands on the table at the origin; the other parts wait in a row behind it (for the
robot, in two rows with room for its hand). ``step_connectors`` says which connectors a step
joins, which fixes each part's designed pose relative to the part it is joined to.
``laid_out_scene`` opens a physics scene with every part at its start.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import NamedTuple

from causalplan.objects.model import AssemblyObject, Connector
from causalplan.sim.geometry import Box, Solid, bounding_box, corners, mating_pose, solids
from causalplan.sim.mechanism import Joint
from causalplan.sim.motions import MOTIONS
from causalplan.sim.plan_steps import StepRequest
from causalplan.sim.poses import Pose
from causalplan.sim.scene import Scene

ROW_GAP = 0.04
"""Metres between parts waiting on the table, and between them and the assembly."""
ROBOT_ROW_GAP = 0.12
"""The same when the robot fetches them: room for its hand (21 cm across) between the parts."""


def step_connectors(
    obj: AssemblyObject, request: StepRequest, joints: list[Joint]
) -> tuple[Connector, Connector] | None:
    """Return the connectors a step joins: its fit's, or a free pair with the same spec."""
    moving, fixed = obj.part(request.moving), obj.part(request.fixed)
    by_id = {(part.id, connector.id): connector for part in obj.parts for connector in part.connectors}
    if request.fit is not None:
        fit = obj.fit(request.fit)
        return by_id[(fit.moving_part, fit.moving_connector)], by_id[(fit.fixed_part, fit.fixed_connector)]
    taken = {(joint.fixed, joint.fixed_connector) for joint in joints if not joint.touch_only}
    pairs = [(m, f) for m in moving.connectors for f in fixed.connectors if m.spec == f.spec]
    pairs.sort(key=lambda pair: (fixed.id, pair[1].id) in taken)
    return pairs[0] if pairs else None


def catalog_fit(obj: AssemblyObject, request: StepRequest, pair: tuple[Connector, Connector]) -> str | None:
    """Return the catalog fit a step makes (given, or the one joining the same connectors)."""
    if request.fit is not None:
        return request.fit
    for fit in obj.fits:
        if fit.connectors() == ((request.moving, pair[0].id), (request.fixed, pair[1].id)):
            return fit.id
    return None


def designed_poses(obj: AssemblyObject, parts: dict[str, Solid], requests: tuple[StepRequest, ...]) -> dict[str, Pose]:
    """Return where the plan means each part it joins to end up: the base at the origin, the rest at their seats."""
    base = parts[obj.base]
    design = {
        obj.base: Pose((-(base.lower[0] + base.upper[0]) / 2, -(base.lower[1] + base.upper[1]) / 2, -base.lower[2]))
    }
    joints: list[Joint] = []
    for request in requests:
        pair = step_connectors(obj, request, joints)
        if pair is None or request.fixed not in design or request.moving in design:
            continue
        if MOTIONS[request.action].touches_only:
            continue
        relative = mating_pose(parts[request.moving].frames[pair[0].id], parts[request.fixed].frames[pair[1].id])
        design[request.moving] = design[request.fixed] * relative
        joints.append(Joint(0, None, request.moving, pair[0].id, request.fixed, pair[1].id))
    return design


def layout(
    obj: AssemblyObject, parts: dict[str, Solid], requests: tuple[StepRequest, ...], gap: float = ROW_GAP
) -> tuple[dict[str, Pose], Box]:
    """Return where each part starts, and the bounds of the assembly the plan means to build.

    The base stands at the origin; the other parts wait in a row behind where the assembly
    will be (for the robot, in two rows, behind and in front, so that all are in its reach).
    The designed bounds (every part at its seat, lights included) frame the camera.
    """
    design = designed_poses(obj, parts, requests)
    homes = {obj.base: design[obj.base]}
    lower, upper = bounding_box(
        pose.apply(corner) for part, pose in design.items() for corner in corners(parts[part].drawn_bounds)
    )
    waiting = [part for part in parts if part != obj.base]
    rows = [waiting[0::2], waiting[1::2]] if gap == ROBOT_ROW_GAP else [waiting]
    for side, row_parts in zip((1.0, -1.0), rows, strict=False):
        widths = [parts[part].upper[0] - parts[part].lower[0] for part in row_parts]
        left = -(sum(widths) + gap * (len(row_parts) - 1)) / 2
        for part, width in zip(row_parts, widths, strict=True):
            solid = parts[part]
            row = upper[1] + gap - solid.lower[1] if side > 0 else lower[1] - gap - solid.upper[1]
            homes[part] = Pose((left - solid.lower[0], row, -solid.lower[2]))
            left += width + gap
    return homes, (lower, upper)


class LaidOut(NamedTuple):
    """A scene with every part at its start, where they started, and the designed assembly's bounds."""

    scene: Scene
    homes: dict[str, Pose]
    design: Box


@contextmanager
def laid_out_scene(
    obj: AssemblyObject,
    requests: tuple[StepRequest, ...],
    gap: float = ROW_GAP,
    *,
    drawn: bool = False,
    still: bool = False,
) -> Iterator[LaidOut]:
    """Open a scene of ``obj``'s parts laid out for ``requests`` (``layout``); the base is dynamic unless ``still``."""
    parts = solids(obj)
    homes, design = layout(obj, parts, requests, gap)
    with Scene(parts, drawn=drawn) as scene:
        for part, pose in homes.items():
            scene.add_part(part, pose, dynamic=part == obj.base and not still)
        yield LaidOut(scene, homes, design)
