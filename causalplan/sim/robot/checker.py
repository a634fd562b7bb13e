"""An independent check of motor commands: velocity, acceleration and jerk recomputed from positions and times.

``violations(trajectory)`` reads only each point's ``time_from_start``, positions and gripper
width (never the velocities a file claims), recomputes velocity, acceleration and jerk by
finite differences (each at the middle of the times it spans) and compares every value with
the robot's datasheet limits: a ratio above 1 is a violation. A position's ratio is its
distance from the middle of the joint's range over half the range.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from causalplan.sim.robot.limits import RobotLimits

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from causalplan.sim.robot.trajectory import Trajectory

QUANTITIES = ("position", "velocity", "acceleration", "jerk", "gripper_width", "gripper_speed")
UNITS = {
    "position": "rad",
    "velocity": "rad/s",
    "acceleration": "rad/s^2",
    "jerk": "rad/s^3",
    "gripper_width": "m",
    "gripper_speed": "m/s",
}


@dataclass(frozen=True)
class Violation:
    """One value beyond a limit: which quantity of which joint, when, by how much."""

    quantity: str
    joint: str
    time: float
    value: float
    limit: float
    ratio: float

    def as_dict(self) -> dict[str, object]:
        return {
            "quantity": self.quantity,
            "joint": self.joint,
            "time": round(self.time, 4),
            "value": round(self.value, 4),
            "limit": self.limit,
            "unit": UNITS[self.quantity],
            "ratio": round(self.ratio, 3),
        }

    def text(self) -> str:
        unit = UNITS[self.quantity]
        return (
            f"{self.joint} {self.quantity} {self.value:.4g} {unit} at {self.time:.3f} s: "
            f"{self.ratio:.2f}x its limit {self.limit:g} {unit}"
        )


def _differences(values: NDArray[np.float64], times: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """Return the finite-difference derivative of ``values`` over ``times``, and the times it is at."""
    import numpy as np

    spans = np.diff(times)
    return np.diff(values, axis=0) / spans[:, None], (times[:-1] + times[1:]) / 2


def _beyond(
    quantity: str,
    names: tuple[str, ...],
    times: NDArray[np.float64],
    values: NDArray[np.float64],
    ratios: NDArray[np.float64],
    limits: NDArray[np.float64],
) -> list[Violation]:
    """Return a violation for every value whose ratio is above 1 (``limits``: the limit of each value)."""
    import numpy as np

    limits = np.broadcast_to(limits, values.shape)
    found = []
    for index, joint in zip(*np.nonzero(ratios > 1.0), strict=True):
        found.append(
            Violation(
                quantity,
                names[joint],
                float(times[index]),
                float(values[index, joint]),
                float(limits[index, joint]),
                float(ratios[index, joint]),
            )
        )
    return found


def violations(trajectory: Trajectory, limits: RobotLimits | None = None) -> list[Violation]:
    """Return every value of ``trajectory`` beyond ``limits`` (default: its robot's datasheet), in time order."""
    import numpy as np

    limits = limits or trajectory.limits
    names = limits.joints
    times = np.array([point.time for point in trajectory.points])
    positions = np.array([point.positions for point in trajectory.points])
    low, high = np.array(limits.position_min), np.array(limits.position_max)
    middle, half = (low + high) / 2, (high - low) / 2
    bounds = np.where(positions < middle, low, high)
    found = _beyond("position", names, times, positions, np.abs(positions - middle) / half, bounds)
    values, at = positions, times
    for quantity, bound in (
        ("velocity", limits.velocity),
        ("acceleration", limits.acceleration),
        ("jerk", limits.jerk),
    ):
        if len(at) < 2:
            break
        values, at = _differences(values, at)
        limit = np.array(bound)
        found += _beyond(quantity, names, at, values, np.abs(values) / limit, limit)
    widths = np.array([[point.gripper_width] for point in trajectory.points])
    gripper = (" and ".join(limits.gripper_joints) or "gripper",)
    width_ratio = np.where(widths < 0, np.inf, widths / limits.gripper_width_max)
    found += _beyond("gripper_width", gripper, times, widths, width_ratio, np.array([limits.gripper_width_max]))
    if len(times) >= 2:
        speeds, at = _differences(widths, times)
        speed = np.array([limits.gripper_speed])
        found += _beyond("gripper_speed", gripper, at, speeds, np.abs(speeds) / speed, speed)
    return sorted(found, key=lambda violation: (violation.time, violation.joint, violation.quantity))
