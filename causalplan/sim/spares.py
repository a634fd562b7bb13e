"""Where the spares of a troubleshooting episode wait on the table for the robot."""

from __future__ import annotations

from causalplan.objects.model import AssemblyObject
from causalplan.sim.geometry import Solid
from causalplan.sim.layout import ROBOT_ROW_GAP
from causalplan.sim.poses import Pose

SPARE = ":spare"
"""The suffix of a spare's id in the scene and the player's document (``light_bulb:spare``)."""
ASIDE = ":aside"
"""The suffix of the free place beside a spare base where the robot sets the broken base down."""
SPARE_ROW_GAP = 0.08
"""Metres between the spares' row and the row of parts before it: room for the hand, and within reach."""
SPARE_ROW_X = -0.1
"""Where (metres along the robot's x axis) the spares' rows are centred: a little nearer the robot than the object."""


def spare_homes(
    obj: AssemblyObject, parts: dict[str, Solid], homes: dict[str, Pose], spares: list[str], base_aside: bool = False
) -> dict[str, Pose]:
    """Return where each spare waits: in a row of spares beyond its part's row on the table.

    The object's own parts keep the places ``layout`` gives them (which ``simulate --robot``
    uses), so the spares do not push them out of the arm's reach. With ``base_aside``, a spare
    base has a free place in the other row of spares (``BASE:aside``), where the robot sets
    the broken base down before it carries the spare to where that stood.
    """
    outer = {1.0: 0.0, -1.0: 0.0}
    for part, pose in homes.items():
        solid = parts[part]
        outer[1.0] = max(outer[1.0], pose.position[1] + solid.upper[1])
        outer[-1.0] = max(outer[-1.0], -(pose.position[1] + solid.lower[1]))
    rows: dict[float, list[tuple[str, str]]] = {1.0: [], -1.0: []}
    for part in spares:
        side = -1.0 if part != obj.base and homes[part].position[1] < 0 else 1.0
        rows[side].append((part, part + SPARE))
        if part == obj.base and base_aside:  # across the object from its spare, so that the spares keep their places
            rows[-side].append((part, part + ASIDE))
    placed: dict[str, Pose] = {}
    for side, row in rows.items():
        widths = [parts[part].upper[0] - parts[part].lower[0] for part, _ in row]
        left = SPARE_ROW_X - (sum(widths) + ROBOT_ROW_GAP * (len(row) - 1)) / 2
        for (part, place), width in zip(row, widths, strict=True):
            solid = parts[part]
            y = (
                outer[side] + SPARE_ROW_GAP - solid.lower[1]
                if side > 0
                else -outer[side] - SPARE_ROW_GAP - solid.upper[1]
            )
            placed[place] = Pose((left - solid.lower[0], y, -solid.lower[2]))
            left += width + ROBOT_ROW_GAP
    return placed
