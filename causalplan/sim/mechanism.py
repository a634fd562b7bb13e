"""The object's true mechanism, judged on the simulated assembly rather than on the plan's words.

A requirement of the catalog ("the light bulb is screwed into the socket") holds when one of
its fits was made in the simulation *and* still holds physically: the two connectors are
still seated within the alignment tolerance, and the part is joined, through seated joints,
to the base (where the power or the fuel is). A lighting fit holds when the flame touched
the tip and the lit part is joined to the base in the same way. A requirement with an order
(``after``: the fuel there before the wick is lit) holds only when each fit it names was made
at an earlier step than its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from causalplan.objects.model import AssemblyObject, Fit
from causalplan.sim.checks import ALIGNMENT_TOLERANCE_DEG, ALIGNMENT_TOLERANCE_MM
from causalplan.sim.outcomes import RequirementCheck
from causalplan.sim.poses import angle_between, distance, scale
from causalplan.sim.scene import Scene


@dataclass(frozen=True)
class Joint:
    """A connection the simulation made: two connectors of two parts, by one step."""

    step: int
    fit: str | None
    moving: str
    moving_connector: str
    fixed: str
    fixed_connector: str
    touch_only: bool = False  # lighting: the parts touched, then the flame went back

    def matches(self, fit: Fit) -> bool:
        """Return whether this joint is the catalog's ``fit`` (by id, or by the same connectors)."""
        return self.fit == fit.id or (
            (self.moving, self.moving_connector, self.fixed, self.fixed_connector)
            == (fit.moving_part, fit.moving_connector, fit.fixed_part, fit.fixed_connector)
        )


def seat_error(scene: Scene, joint: Joint) -> tuple[float, float]:
    """Return how far (mm) and how tilted (degrees) a joint's two connectors are from meeting."""
    moving_frame = scene.solids[joint.moving].frames[joint.moving_connector]
    fixed_frame = scene.solids[joint.fixed].frames[joint.fixed_connector]
    moving_pose, fixed_pose = scene.pose(joint.moving), scene.pose(joint.fixed)
    offset = distance(moving_pose.apply(moving_frame.position), fixed_pose.apply(fixed_frame.position))
    tilt = angle_between(moving_pose.turn(moving_frame.axis), scale(fixed_pose.turn(fixed_frame.axis), -1.0))
    return offset * 1000, math.degrees(tilt)


def is_seated(offset_mm: float, tilt_deg: float) -> bool:
    """Return whether a joint's seat error (``seat_error``) is within the alignment tolerances."""
    return offset_mm <= ALIGNMENT_TOLERANCE_MM and tilt_deg <= ALIGNMENT_TOLERANCE_DEG


def joined_to_base(base: str, holding: list[Joint]) -> set[str]:
    """Return the parts joined to ``base`` through the ``holding`` joints."""
    joined, frontier = {base}, [base]
    while frontier:
        part = frontier.pop()
        for joint in holding:
            for a, b in ((joint.fixed, joint.moving), (joint.moving, joint.fixed)):
                if a == part and b not in joined:
                    joined.add(b)
                    frontier.append(b)
    return joined


def _judge(
    obj: AssemblyObject, fit: Fit, joints: list[Joint], errors: dict[Joint, tuple[float, float]], joined: set[str]
) -> tuple[bool, str]:
    """Return whether ``fit`` holds in the simulated assembly, and what was seen (``errors``: joints' seat errors)."""
    made = [joint for joint in joints if joint.matches(fit)]
    moving, fixed = obj.part(fit.moving_part).name, obj.part(fit.fixed_part).name
    base = obj.part(obj.base).name
    if not made:
        return False, f"never done: no step joined the {moving} to the {fixed}"
    joint = made[-1]
    if joint.touch_only:
        if fit.fixed_part in joined:
            return True, f"the {fixed} lit at step {joint.step}, and joined to the {base}"
        return False, f"the {fixed} lit at step {joint.step}, but not joined to the {base}"
    offset_mm, tilt_deg = errors[joint]
    where = f"{offset_mm:.1f} mm and {tilt_deg:.1f}° from the seat"
    if not is_seated(offset_mm, tilt_deg):
        return False, f"the {moving} off the {fixed}: {where}"
    if fit.moving_part not in joined:
        return False, f"the {moving} on the {fixed} ({where}), but not joined to the {base}"
    return True, f"the {moving} seated on the {fixed} ({where})"


def _too_early(obj: AssemblyObject, after: tuple[str, ...], fit: Fit, joints: list[Joint]) -> str | None:
    """Return how ``fit`` (made, as ``joints`` show) came before a fit ``after`` names, or None when in order."""
    step = max(joint.step for joint in joints if joint.matches(fit))
    for earlier_id in after:
        earlier = obj.fit(earlier_id)
        steps = [joint.step for joint in joints if joint.matches(earlier)]
        what = obj.step_text(earlier).rstrip(".").lower()
        if not steps:
            return f"'{what}' never was, and must come first"
        if min(steps) >= step:
            return f"that was before '{what}' (step {min(steps)}), which must come first"
    return None


def evaluate(obj: AssemblyObject, scene: Scene, joints: list[Joint]) -> tuple[RequirementCheck, ...]:
    """Return each requirement of the true mechanism, judged on the simulated assembly now."""
    errors = {joint: seat_error(scene, joint) for joint in joints if not joint.touch_only}
    joined = joined_to_base(obj.base, [joint for joint, error in errors.items() if is_seated(*error)])
    checks = []
    for requirement in obj.mechanism:
        seen = []
        for fit_id in requirement.any_of:
            met, detail = _judge(obj, obj.fit(fit_id), joints, errors, joined)
            too_early = _too_early(obj, requirement.after, obj.fit(fit_id), joints) if met else None
            if too_early is not None:
                met, detail = False, f"{detail}; but {too_early}"
            if met:
                checks.append(RequirementCheck(requirement.says, True, fit_id, detail))
                break
            seen.append(detail)
        else:
            checks.append(RequirementCheck(requirement.says, False, None, "; ".join(seen)))
    return tuple(checks)
