"""What the simulator checks, with which tolerances: each check is a measured figure against a limit.

The tolerances are named here, once, and copied into every report so that a reader knows
what "passed" meant.
"""

from __future__ import annotations

from causalplan.objects.model import Connector
from causalplan.sim.outcomes import Check

PENETRATION_TOLERANCE_MM = 1.0
"""Deepest overlap allowed between the moving part and anything else along its approach."""
CONTACT_TOLERANCE_MM = 1.0
"""Largest gap allowed between a part and the part it is joined to, once in place."""
ALIGNMENT_TOLERANCE_MM = 2.0
"""Largest distance allowed between two joined connectors' meeting points."""
ALIGNMENT_TOLERANCE_DEG = 2.0
"""Largest angle allowed between two joined connectors' (opposed) axes."""
STABILITY_TOLERANCE_MM = 5.0
"""Largest drift of any assembled part while the assembly settles."""
STABILITY_TOLERANCE_DEG = 5.0
"""Largest tilt of any assembled part while the assembly settles."""
REACH_TOLERANCE_MM = 10.0
"""Largest distance between the robot's gripper and a grasp pose for the pose to count as reached."""
STEP_SETTLE_SECONDS = 0.1
"""Physics time after each step that fastens or places a part."""
FINAL_SETTLE_SECONDS = 0.5
"""Physics time after the last step, before stability and the true mechanism are judged."""

TOLERANCES: dict[str, float] = {
    "penetration_mm": PENETRATION_TOLERANCE_MM,
    "contact_mm": CONTACT_TOLERANCE_MM,
    "alignment_mm": ALIGNMENT_TOLERANCE_MM,
    "alignment_deg": ALIGNMENT_TOLERANCE_DEG,
    "stability_mm": STABILITY_TOLERANCE_MM,
    "stability_deg": STABILITY_TOLERANCE_DEG,
    "reach_mm": REACH_TOLERANCE_MM,
    "step_settle_s": STEP_SETTLE_SECONDS,
    "final_settle_s": FINAL_SETTLE_SECONDS,
}


def connectors_check(moving_name: str, moving: Connector, fixed_name: str, fixed: Connector) -> Check:
    """Return whether two connectors fit: they share a spec."""
    fits = moving.spec == fixed.spec
    detail = (
        f"the {moving_name}'s {moving.kind} ({moving.spec}) "
        f"{'fits' if fits else 'does not fit'} the {fixed_name}'s {fixed.kind} ({fixed.spec})"
    )
    return Check("connectors", fits, detail)


def path_check(depth_mm: float, moving_name: str, hit_name: str | None = None, short_of_seat_mm: float = 0.0) -> Check:
    """Return whether the approach path was clear: the deepest overlap met on the way in."""
    passed = depth_mm <= PENETRATION_TOLERANCE_MM
    if hit_name is None:
        detail = f"the {moving_name} reached the seat; deepest overlap on the way {depth_mm:.1f} mm"
    else:
        detail = (
            f"the {moving_name} blocked by the {hit_name}, {short_of_seat_mm:.1f} mm before the seat "
            f"(overlap {depth_mm:.1f} mm)"
        )
    return Check("path", passed, detail, round(depth_mm, 2), PENETRATION_TOLERANCE_MM, "mm")


def contact_check(gap_mm: float, moving_name: str, fixed_name: str) -> Check:
    """Return whether the joined parts touch (a part cannot be joined in mid-air)."""
    passed = gap_mm <= CONTACT_TOLERANCE_MM
    detail = f"the {moving_name} {'in' if passed else 'not in'} contact with the {fixed_name} (gap {gap_mm:.1f} mm)"
    return Check("contact", passed, detail, round(gap_mm, 2), CONTACT_TOLERANCE_MM, "mm")


def alignment_check(offset_mm: float, angle_deg: float) -> tuple[Check, Check]:
    """Return the position and angle checks of two joined connectors."""
    position = Check(
        "alignment",
        offset_mm <= ALIGNMENT_TOLERANCE_MM,
        f"the connectors meet {offset_mm:.1f} mm apart",
        round(offset_mm, 2),
        ALIGNMENT_TOLERANCE_MM,
        "mm",
    )
    angle = Check(
        "alignment_angle",
        angle_deg <= ALIGNMENT_TOLERANCE_DEG,
        f"the connector axes are {angle_deg:.1f}° off opposite",
        round(angle_deg, 2),
        ALIGNMENT_TOLERANCE_DEG,
        "deg",
    )
    return position, angle


def stability_checks(moved_mm: float, turned_deg: float, part_name: str | None, seconds: float) -> tuple[Check, Check]:
    """Return whether the assembly held still while it settled: largest drift and tilt of a part."""
    what = f"the {part_name}" if part_name else "no part"
    drift = Check(
        "stability",
        moved_mm <= STABILITY_TOLERANCE_MM,
        f"{what} moved most: {moved_mm:.1f} mm in {seconds:g} s",
        round(moved_mm, 2),
        STABILITY_TOLERANCE_MM,
        "mm",
    )
    tilt = Check(
        "stability_angle",
        turned_deg <= STABILITY_TOLERANCE_DEG,
        f"largest tilt of a part {turned_deg:.1f}° in {seconds:g} s",
        round(turned_deg, 2),
        STABILITY_TOLERANCE_DEG,
        "deg",
    )
    return drift, tilt
