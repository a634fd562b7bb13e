"""Each part as a solid: its shapes, mass, centre, bounds and connector frames, with defaults.

A part without geometry in its catalog file becomes a plain cylinder (5 cm across and
high: it can be screwed in on any face without sweeping into the table), and a connector
without a frame is put on a face of the part's bounds: a connector the part is attached *by*
goes on the bottom face, the others on the top and side faces in turn. So a user's own
object can be simulated before anyone describes its shapes.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable
from dataclasses import dataclass

from causalplan import caches
from causalplan.caches import BoundedCache
from causalplan.objects.model import AssemblyObject, Part, Shape, Vector
from causalplan.sim.poses import Pose, about_axis, add, from_rpy, multiply, rotate, scale, shortest_arc

DEFAULT_SIZE: Vector = (0.05, 0.05, 0.05)
"""Diameter, diameter and height of the cylinder a part without geometry becomes."""
DEFAULT_MASS = 0.1
DEFAULT_COLORS: tuple[tuple[float, float, float, float], ...] = (
    (0.35, 0.55, 0.80, 1.0),
    (0.85, 0.55, 0.25, 1.0),
    (0.45, 0.70, 0.40, 1.0),
    (0.75, 0.40, 0.55, 1.0),
    (0.55, 0.50, 0.80, 1.0),
    (0.80, 0.75, 0.35, 1.0),
)
"""Colours of default parts, by the part's position in its object (deterministic)."""

Box = tuple[Vector, Vector]
"""An axis-aligned box: its lower and upper corners."""

# Faces for connectors without a frame: (outward axis), in the order they are handed out.
_FACES: tuple[Vector, ...] = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0))
_BOTTOM: Vector = (0.0, 0.0, -1.0)


@dataclass(frozen=True)
class Frame:
    """A connector's frame in its part's frame: the meeting point and the outward axis."""

    position: Vector
    axis: Vector


@dataclass(frozen=True)
class Solid:
    """A part as the simulator builds it (all lengths in metres, in the part's frame)."""

    part_id: str
    name: str
    shapes: tuple[Shape, ...]
    mass: float
    light: tuple[Shape, ...]
    frames: dict[str, Frame]
    lower: Vector
    upper: Vector
    center: Vector
    has_own_geometry: bool

    @functools.cached_property
    def drawn_bounds(self) -> Box:
        """Return the bounds of the part's shapes and its light (worked out once per solid)."""
        return bounds(self.shapes + self.light)

    @property
    def radius(self) -> float:
        """Return the radius of a sphere around ``center`` that holds the whole part."""
        return max(math.dist(self.center, corner) for corner in corners((self.lower, self.upper)))


def corners(box: Box) -> tuple[Vector, ...]:
    """Return the eight corners of ``box``."""
    (x0, y0, z0), (x1, y1, z1) = box
    return tuple((x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1))


def bounding_box(points: Iterable[Vector]) -> Box:
    """Return the smallest axis-aligned box holding every point."""
    xs, ys, zs = zip(*points, strict=True)
    return (min(xs), min(ys), min(zs)), (max(xs), max(ys), max(zs))


def shape_bounds(shape: Shape) -> Box:
    """Return the axis-aligned bounds of one shape in its part's frame (rotation included)."""
    half = scale(shape.size, 0.5)
    orientation = from_rpy(shape.rotation)
    turned = (rotate(orientation, corner) for corner in corners((scale(half, -1.0), half)))
    return bounding_box(add(shape.position, corner) for corner in turned)


def bounds(shapes: tuple[Shape, ...]) -> Box:
    """Return the axis-aligned bounds of several shapes."""
    return bounding_box(corner for shape in shapes for corner in shape_bounds(shape))


def _volume(shape: Shape) -> float:
    x, y, z = shape.size
    if shape.kind == "sphere":
        return math.pi * x**3 / 6
    if shape.kind == "cylinder":
        return math.pi * x * y * z / 4
    return x * y * z


def centroid(shapes: tuple[Shape, ...]) -> Vector:
    """Return the centre of volume of the shapes (the part's centre of mass, at uniform density)."""
    volumes = [_volume(shape) for shape in shapes]
    total = sum(volumes)
    x, y, z = (sum(v * shape.position[i] for v, shape in zip(volumes, shapes, strict=True)) / total for i in range(3))
    return (x, y, z)


def _default_frames(part: Part, lower: Vector, upper: Vector, moving: set[tuple[str, str]]) -> dict[str, Frame]:
    """Return a frame for every connector of ``part``: its own, or one on a face of the bounds."""
    middle = scale(add(lower, upper), 0.5)
    frames: dict[str, Frame] = {}
    next_face = 0
    for connector in part.connectors:
        if connector.position is not None and connector.axis is not None:
            frames[connector.id] = Frame(connector.position, connector.axis)
            continue
        if connector.axis is not None:
            axis = connector.axis
        elif (part.id, connector.id) in moving:
            axis = _BOTTOM
        else:
            axis = _FACES[next_face % len(_FACES)]
            next_face += 1
        frames[connector.id] = Frame(connector.position or _exit_point(middle, lower, upper, axis), axis)
    return frames


def _exit_point(middle: Vector, lower: Vector, upper: Vector, axis: Vector) -> Vector:
    """Return where a ray from ``middle`` along ``axis`` leaves the box ``lower``..``upper``."""
    travel = min(((upper[i] if axis[i] > 0 else lower[i]) - middle[i]) / axis[i] for i in range(3) if axis[i] != 0)
    return add(middle, scale(axis, travel))


def solid_of(part: Part, index: int, moving: set[tuple[str, str]]) -> Solid:
    """Return the solid of one part (``index`` picks a default part's colour)."""
    if part.geometry is not None:
        shapes, mass, light = part.geometry.shapes, part.geometry.mass, part.geometry.light
    else:
        color = DEFAULT_COLORS[index % len(DEFAULT_COLORS)]
        cylinder = Shape("cylinder", DEFAULT_SIZE, (0.0, 0.0, DEFAULT_SIZE[2] / 2), color=color)
        shapes, mass, light = (cylinder,), DEFAULT_MASS, ()
    lower, upper = bounds(shapes)
    return Solid(
        part_id=part.id,
        name=part.name,
        shapes=shapes,
        mass=mass,
        light=light,
        frames=_default_frames(part, lower, upper, moving),
        lower=lower,
        upper=upper,
        center=centroid(shapes),
        has_own_geometry=part.geometry is not None,
    )


def solids(obj: AssemblyObject) -> dict[str, Solid]:
    """Return every part of ``obj`` as a solid, by part id.

    Kept (the process's ``solids`` cache), since objects are immutable: callers share the dict
    and must not change it.
    """
    kept: BoundedCache[AssemblyObject, dict[str, Solid]] = caches.current().solids
    return kept.get_or_make(obj, lambda: _solids(obj))


def _solids(obj: AssemblyObject) -> dict[str, Solid]:
    moving = {(fit.moving_part, fit.moving_connector) for fit in obj.fits}
    return {part.id: solid_of(part, index, moving) for index, part in enumerate(obj.parts)}


def mating_pose(moving: Frame, fixed: Frame, spin: float = 0.0) -> Pose:
    """Return the moving part's pose in the fixed part's frame when their connectors meet.

    The two meeting points coincide and the axes point at each other. ``spin`` turns the
    moving part about the common axis (a screw's turns on the way in).
    """
    target_axis = scale(fixed.axis, -1.0)
    orientation = multiply(about_axis(target_axis, spin), shortest_arc(moving.axis, target_axis))
    offset = rotate(orientation, moving.position)
    return Pose(
        (fixed.position[0] - offset[0], fixed.position[1] - offset[1], fixed.position[2] - offset[2]), orientation
    )
