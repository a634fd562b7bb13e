"""Each robot model's joint limits, from its maker's datasheet (not its URDF): one table per model.

The Panda's come from Franka's published robot and interface specifications (FCI
documentation, "Limits for Panda"): joint positions, velocities, accelerations, jerks and
torques, and the Franka Hand's opening and speed. pybullet_data's ``panda.urdf`` allows more
(joint 7 to ±2.9671 rad against the real ±2.8973): IK and motion planning use these positions,
``POSITION_MARGIN`` inside them; time parameterization scales the rest by a safety factor.
"""

from __future__ import annotations

from dataclasses import dataclass

from causalplan.errors import CausalPlanError

POSITION_MARGIN = 0.02
"""Radians kept clear of every datasheet position limit by IK and motion planning."""
DEFAULT_SAFETY_FACTOR = 0.5
"""The share of the datasheet's velocity and acceleration limits a trajectory is timed to, by default.

Jerk, which time parameterization does not bound, is checked against the datasheet itself."""


class UnknownRobotError(CausalPlanError):
    """A robot model no limits table is known for."""

    code = "unknown_robot"


@dataclass(frozen=True)
class RobotLimits:
    """A robot model's datasheet limits, per arm joint (radians, seconds, newton metres) and for its gripper."""

    model: str
    joints: tuple[str, ...]
    position_min: tuple[float, ...]
    position_max: tuple[float, ...]
    velocity: tuple[float, ...]
    acceleration: tuple[float, ...]
    jerk: tuple[float, ...]
    torque: tuple[float, ...]
    gripper_joints: tuple[str, ...]
    gripper_width_max: float
    """Metres between the fingers, fully open."""
    gripper_speed: float
    """Metres a second the gripper's width changes at most."""
    gripper_force: float
    """Newtons each finger pushes with, continuously."""
    source: str

    def scaled(self, factor: float) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
        """Return the velocity, acceleration and jerk limits times ``factor``."""
        return (
            tuple(v * factor for v in self.velocity),
            tuple(a * factor for a in self.acceleration),
            tuple(j * factor for j in self.jerk),
        )

    def as_dict(self, safety_factor: float) -> dict[str, object]:
        """Return the limits as JSON, with the safety factor a trajectory was made within."""
        return {
            "model": self.model,
            "source": self.source,
            "safety_factor": safety_factor,
            "position_min": list(self.position_min),
            "position_max": list(self.position_max),
            "velocity": list(self.velocity),
            "acceleration": list(self.acceleration),
            "jerk": list(self.jerk),
            "torque": list(self.torque),
            "gripper_width_max": self.gripper_width_max,
            "gripper_speed": self.gripper_speed,
        }


PANDA = RobotLimits(
    model="panda",
    joints=tuple(f"panda_joint{number}" for number in range(1, 8)),
    position_min=(-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973),
    position_max=(2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973),
    velocity=(2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61),
    acceleration=(15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0),
    jerk=(7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0),
    torque=(87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0),
    gripper_joints=("panda_finger_joint1", "panda_finger_joint2"),
    gripper_width_max=0.08,
    gripper_speed=0.1,
    gripper_force=70.0,
    source="Franka Emika, Panda datasheet and FCI 'Limits for Panda'",
)
ROBOTS: dict[str, RobotLimits] = {PANDA.model: PANDA}
"""Every robot model with a limits table, by name."""


def robot_limits(model: str) -> RobotLimits:
    """Return the limits of robot ``model``; UnknownRobotError names the models known."""
    try:
        return ROBOTS[model]
    except KeyError:
        raise UnknownRobotError(f"No limits are known for the robot {model!r}; known: {', '.join(ROBOTS)}.") from None
