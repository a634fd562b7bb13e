"""What the robot's run of a troubleshooting episode shows: each action in physics, and the whole run."""

from __future__ import annotations

from dataclasses import dataclass, field

from causalplan.sim.outcomes import RequirementCheck
from causalplan.sim.poses import Pose
from causalplan.sim.robot.motors import MotorRun
from causalplan.sim.robot.tracks import PartTrack
from causalplan.sim.robot.trajectory import Trajectory


@dataclass(frozen=True)
class ActionInPhysics:
    """What the robot did for one action of the episode, and what physics showed."""

    number: int
    kind: str
    part: str | None
    motions: tuple[str, ...]
    """The robot's motions (transit, grasp, carry, approach, screw, push, ignite, release, retreat)."""
    observed: str | None = None
    """For a test: ``goal`` or ``no goal`` in physics (the mechanism, and the broken part replaced)."""
    failure: str | None = None
    message: str = ""

    @property
    def passed(self) -> bool:
        return self.failure is None

    def as_dict(self) -> dict[str, object]:
        return {
            "number": self.number,
            "action": self.kind,
            "part": self.part,
            "robot": list(self.motions),
            "observed": self.observed,
            "passed": self.passed,
            "failure": self.failure,
            "message": self.message,
        }


@dataclass(frozen=True)
class EpisodeInPhysics:
    """The robot's run of an episode: each action, the last test's mechanism, its motor commands and tracks."""

    object_id: str
    actions: tuple[ActionInPhysics, ...]
    requirements: tuple[RequirementCheck, ...]
    """The true mechanism at the last test the robot made."""
    broken_part_replaced: bool
    commands: Trajectory | None
    tracks: dict[str, PartTrack]
    placed: dict[str, Pose]
    """Where every body (spares by their ``:spare`` id) is at the end."""
    timing: dict[str, float] = field(default_factory=dict)
    motors: MotorRun | None = None
    """The commands played through the Panda's joint motors in a fresh scene (``robot_episode(..., motors=True)``)."""

    @property
    def carried_out(self) -> bool:
        return all(action.passed for action in self.actions)

    @property
    def mechanism_works(self) -> bool:
        return bool(self.requirements) and all(requirement.met for requirement in self.requirements)

    @property
    def produces_goal(self) -> bool:
        """Return whether the robot carried out every action and its last test showed the goal in physics.

        Driven by its motors too, when it was: the motors' run must also give the goal.
        """
        by_motors = self.motors is None or self.motors.produces_goal
        return self.carried_out and self.mechanism_works and self.broken_part_replaced and by_motors

    @property
    def failed(self) -> ActionInPhysics | None:
        return next((action for action in self.actions if not action.passed), None)

    def as_dict(self) -> dict[str, object]:
        return {
            "produces_goal": self.produces_goal,
            "carried_out": self.carried_out,
            "broken_part_replaced": self.broken_part_replaced,
            "actions": [action.as_dict() for action in self.actions],
            "mechanism": [check.as_dict() for check in self.requirements],
            "seconds": round(self.commands.seconds, 3) if self.commands is not None else 0.0,
            "timing": {name: round(seconds, 3) for name, seconds in self.timing.items()},
            "motors": self.motors.as_dict() if self.motors is not None else None,
        }
