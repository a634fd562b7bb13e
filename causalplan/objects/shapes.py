"""Part geometry from catalog files: colours, rotations, and tubes built from boxes (pure)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from causalplan.objects.model import Geometry, Shape, Vector

if TYPE_CHECKING:
    from causalplan.objects.schema import GeometrySchema, ShapeSchema

Matrix = tuple[Vector, Vector, Vector]
"""A 3x3 rotation matrix, row by row."""


def parse_color(text: str) -> tuple[float, float, float, float]:
    """Return red, green, blue, alpha in 0..1 from '#rrggbb' or '#rrggbbaa'."""
    digits = text.removeprefix("#")
    channels = [int(digits[index : index + 2], 16) / 255 for index in range(0, len(digits), 2)]
    red, green, blue = channels[:3]
    return (red, green, blue, channels[3] if len(channels) == 4 else 1.0)


def matrix_from_rpy(roll: float, pitch: float, yaw: float) -> Matrix:
    """Return the rotation matrix of roll, pitch, yaw (radians): Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp, cy, sy = (
        math.cos(roll),
        math.sin(roll),
        math.cos(pitch),
        math.sin(pitch),
        math.cos(yaw),
        math.sin(yaw),
    )
    return (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )


def rpy_from_matrix(matrix: Matrix) -> Vector:
    """Return roll, pitch, yaw (radians) of a rotation matrix (the inverse of ``matrix_from_rpy``)."""
    pitch = math.asin(max(-1.0, min(1.0, -matrix[2][0])))
    if abs(matrix[2][0]) < 1.0 - 1e-9:
        return (math.atan2(matrix[2][1], matrix[2][2]), pitch, math.atan2(matrix[1][0], matrix[0][0]))
    # Gimbal lock: roll and yaw turn about the same axis; put it all in yaw.
    return (0.0, pitch, math.atan2(-matrix[0][1], matrix[1][1]))


def multiply(left: Matrix, right: Matrix) -> Matrix:
    """Return the matrix product ``left @ right``."""

    def row(i: int) -> Vector:
        x, y, z = (sum(left[i][k] * right[k][j] for k in range(3)) for j in range(3))
        return (x, y, z)

    return (row(0), row(1), row(2))


def rotate(matrix: Matrix, vector: Vector) -> Vector:
    """Return ``matrix @ vector``."""
    x, y, z = (sum(matrix[i][k] * vector[k] for k in range(3)) for i in range(3))
    return (x, y, z)


def tube_boxes(
    radius: float, top_radius: float, length: float, thickness: float, segments: int
) -> tuple[tuple[Vector, Vector, Vector], ...]:
    """Return the staves of a hollow tube (or cone) around the z axis, centred on the origin.

    Each stave is (size, position, roll-pitch-yaw). Staves are as wide as the chord at the
    larger radius, so neighbours overlap a little and leave no gap to slip through.
    """
    bottom, top = radius - thickness / 2, top_radius - thickness / 2
    lean = math.atan2(bottom - top, length)
    width = 2 * max(radius, top_radius) * math.tan(math.pi / segments)
    size = (thickness, width, math.hypot(length, bottom - top))
    middle = (bottom + top) / 2
    staves = []
    for index in range(segments):
        angle = 2 * math.pi * index / segments
        staves.append((size, (middle * math.cos(angle), middle * math.sin(angle), 0.0), (0.0, -lean, angle)))
    return tuple(staves)


def _place(shape: Shape, position: Vector, rotation: Matrix) -> Shape:
    """Return ``shape`` moved by a rotation, then a translation (a tube's own frame)."""
    x, y, z = rotate(rotation, shape.position)
    turned = rpy_from_matrix(multiply(rotation, matrix_from_rpy(*shape.rotation)))
    return Shape(shape.kind, shape.size, (x + position[0], y + position[1], z + position[2]), turned, shape.color)


def build_shapes(schema: ShapeSchema) -> tuple[Shape, ...]:
    """Return the primitive shapes one catalog shape entry stands for (a tube gives many boxes)."""
    color = parse_color(schema.color)
    rotation: Vector = (math.radians(schema.turn[0]), math.radians(schema.turn[1]), math.radians(schema.turn[2]))
    position: Vector = schema.at
    if schema.shape == "box":
        assert schema.size is not None
        return (Shape("box", schema.size, position, rotation, color),)
    assert schema.radius is not None
    diameter = 2 * schema.radius
    if schema.shape == "sphere":
        return (Shape("sphere", (diameter, diameter, diameter), position, rotation, color),)
    assert schema.length is not None
    if schema.shape == "cylinder":
        return (Shape("cylinder", (diameter, diameter, schema.length), position, rotation, color),)
    assert schema.thickness is not None
    staves = tube_boxes(
        schema.radius, schema.top_radius or schema.radius, schema.length, schema.thickness, schema.segments
    )
    frame = matrix_from_rpy(*rotation)
    return tuple(_place(Shape("box", size, at, turn, color), position, frame) for size, at, turn in staves)


def build_geometry(schema: GeometrySchema) -> Geometry:
    """Return a part's geometry from its (schema-valid) catalog entry."""
    return Geometry(
        shapes=tuple(shape for entry in schema.shapes for shape in build_shapes(entry)),
        mass=schema.mass,
        light=tuple(shape for entry in schema.light for shape in build_shapes(entry)),
    )


def unit(vector: Vector) -> Vector:
    """Return ``vector`` scaled to length 1 (the caller has checked it is not zero)."""
    norm = math.sqrt(sum(component * component for component in vector))
    return (vector[0] / norm, vector[1] / norm, vector[2] / norm)
