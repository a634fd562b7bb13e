"""What a worker process draws for the pages: each part of an object alone, and an object after a plan.

PyBullet never loads in the web server: the pages keep what these drew (``pages.pictures``).
"""

from __future__ import annotations

from dataclasses import dataclass

from causalplan.objects.catalog import Catalog

PART_PICTURE_SIZE = (320, 240)
PLAN_PICTURE_SIZE = (480, 360)


@dataclass(frozen=True)
class PartPicturesArguments:
    """The pictures of every part of one object."""

    object_id: str


@dataclass(frozen=True)
class AssemblyPictureArguments:
    """The picture of the object after the plan that makes ``fit_ids`` in order."""

    object_id: str
    fit_ids: tuple[str, ...]


def part_pictures(arguments: PartPicturesArguments, catalog: Catalog) -> dict[str, bytes]:
    """Return a PNG of each part of an object, alone on the table, by part id."""
    from causalplan.sim.geometry import solids
    from causalplan.sim.render import part_alone

    obj = catalog.get(arguments.object_id)
    return {part_id: part_alone(part_id, solid, PART_PICTURE_SIZE).png() for part_id, solid in solids(obj).items()}


def assembly_picture(arguments: AssemblyPictureArguments, catalog: Catalog) -> bytes:
    """Return a PNG of the object after the plan that makes the fits in order."""
    from causalplan.service.work.robot import steps_of
    from causalplan.sim import RenderMode, simulate_plan

    obj = catalog.get(arguments.object_id)
    report = simulate_plan(obj, steps_of(obj, arguments.fit_ids), render=RenderMode.FINAL, size=PLAN_PICTURE_SIZE)
    assert report.picture is not None, "RenderMode.FINAL always draws the final picture"
    return report.picture.png()
