"""Rigid poses: positions and unit quaternions (x, y, z, w, as PyBullet orders them), pure Python."""

from __future__ import annotations

import math
from dataclasses import dataclass

from causalplan.objects.model import Vector

Quaternion = tuple[float, float, float, float]
IDENTITY: Quaternion = (0.0, 0.0, 0.0, 1.0)


def add(a: Vector, b: Vector) -> Vector:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def scale(vector: Vector, factor: float) -> Vector:
    return (vector[0] * factor, vector[1] * factor, vector[2] * factor)


def dot(a: Vector, b: Vector) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vector, b: Vector) -> Vector:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def distance(a: Vector, b: Vector) -> float:
    """Return the Euclidean distance between two points."""
    return math.dist(a, b)


def normalized(vector: Vector) -> Vector:
    """Return ``vector`` scaled to length 1."""
    return scale(vector, 1.0 / math.sqrt(dot(vector, vector)))


def angle_between(a: Vector, b: Vector) -> float:
    """Return the angle between two directions, in radians."""
    cosine = dot(a, b) / math.sqrt(dot(a, a) * dot(b, b))
    return math.acos(max(-1.0, min(1.0, cosine)))


def multiply(a: Quaternion, b: Quaternion) -> Quaternion:
    """Return the rotation ``b`` followed by ``a`` (the product a * b)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def conjugate(q: Quaternion) -> Quaternion:
    return (-q[0], -q[1], -q[2], q[3])


def rotate(q: Quaternion, vector: Vector) -> Vector:
    """Return ``vector`` rotated by the unit quaternion ``q``."""
    x, y, z, _ = multiply(multiply(q, (vector[0], vector[1], vector[2], 0.0)), conjugate(q))
    return (x, y, z)


def about_axis(axis: Vector, angle: float) -> Quaternion:
    """Return the rotation by ``angle`` radians about the unit ``axis``."""
    s = math.sin(angle / 2)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2))


def from_rpy(rpy: Vector) -> Quaternion:
    """Return the quaternion of roll, pitch, yaw (radians), as ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    roll = about_axis((1.0, 0.0, 0.0), rpy[0])
    pitch = about_axis((0.0, 1.0, 0.0), rpy[1])
    yaw = about_axis((0.0, 0.0, 1.0), rpy[2])
    return multiply(yaw, multiply(pitch, roll))


def shortest_arc(source: Vector, target: Vector) -> Quaternion:
    """Return the smallest rotation that turns the unit ``source`` onto the unit ``target``."""
    cosine = dot(source, target)
    if cosine > 1.0 - 1e-12:
        return IDENTITY
    if cosine < -1.0 + 1e-12:
        # Opposite directions: any perpendicular axis works; take the one nearest to x, then y.
        helper = (1.0, 0.0, 0.0) if abs(source[0]) < 0.9 else (0.0, 1.0, 0.0)
        return about_axis(normalized(cross(source, helper)), math.pi)
    x, y, z = cross(source, target)
    w = 1.0 + cosine
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    return (x / norm, y / norm, z / norm, w / norm)


def rotation_angle(q: Quaternion) -> float:
    """Return the angle (radians, 0..pi) of the rotation ``q``."""
    return 2 * math.acos(min(1.0, abs(q[3])))


@dataclass(frozen=True)
class Pose:
    """A rigid transform: rotate by ``orientation``, then move by ``position`` (metres)."""

    position: Vector = (0.0, 0.0, 0.0)
    orientation: Quaternion = IDENTITY

    def __mul__(self, other: Pose) -> Pose:
        """Return ``other`` (given in this pose's frame) expressed in this pose's parent frame."""
        return Pose(self.apply(other.position), multiply(self.orientation, other.orientation))

    def apply(self, point: Vector) -> Vector:
        """Return ``point`` (in this pose's frame) in the parent frame."""
        return add(rotate(self.orientation, point), self.position)

    def turn(self, direction: Vector) -> Vector:
        """Return ``direction`` (in this pose's frame) in the parent frame."""
        return rotate(self.orientation, direction)

    def inverse(self) -> Pose:
        inverse = conjugate(self.orientation)
        return Pose(scale(rotate(inverse, self.position), -1.0), inverse)

    def translated(self, offset: Vector) -> Pose:
        """Return this pose moved by ``offset`` in the parent frame."""
        return Pose(add(self.position, offset), self.orientation)


def difference(a: Pose, b: Pose) -> tuple[float, float]:
    """Return how far apart two poses are: (metres, radians)."""
    relative = multiply(conjugate(a.orientation), b.orientation)
    return distance(a.position, b.position), rotation_angle(relative)
