"""What a simulation reports: per step, its checks and any failure; then stability and the mechanism."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from causalplan.sim.outcomes import Check, Picture, RequirementCheck, StepReport, StepStatus

if TYPE_CHECKING:
    from causalplan.sim.poses import Pose
    from causalplan.sim.robot.motors import MotorRun
    from causalplan.sim.robot.tracks import PartTrack
    from causalplan.sim.robot.trajectory import Trajectory, Waypoints


@dataclass(frozen=True)
class SimulationReport:
    """The outcome of simulating a plan: per-step checks, stability, the true mechanism, pictures.

    Timings and pictures do not take part in equality, so two runs of the same plan compare equal.
    """

    object_id: str
    object_name: str
    goal: str
    steps: tuple[StepReport, ...]
    stability: tuple[Check, ...]
    unstable_step: int | None
    requirements: tuple[RequirementCheck, ...]
    produces_goal: bool
    tolerances: dict[str, float]
    arm: bool = False
    robot: bool = False
    timing: dict[str, float] = field(default_factory=dict, compare=False)
    picture: Picture | None = field(default=None, compare=False)
    frames: tuple[Picture, ...] = field(default=(), compare=False)
    trajectory: Waypoints | None = field(default=None, compare=False)
    """The robot's planned waypoints, untimed (``robot`` runs only; the film draws them)."""
    motor_commands: Trajectory | None = field(default=None, compare=False)
    """The robot's motor commands: the waypoints time-parameterized within its limits (``robot`` runs only)."""
    motors: MotorRun | None = field(default=None, compare=False)
    """How the motors carried out the motor commands in physics (``robot`` runs with ``motors`` only)."""
    placed: dict[str, Pose] = field(default_factory=dict, compare=False)
    """Where the robot let go of each part it joined (``robot`` runs only), before the assembly settled."""
    video: tuple[Picture, ...] = field(default=(), compare=False)
    """Frames of the robot at work (``robot`` runs with a video only)."""
    tracks: dict[str, PartTrack] = field(default_factory=dict, compare=False)
    """Every part's pose over the motor commands (``robot`` runs with ``tracks`` only), for the browser's player."""

    @property
    def failed_step(self) -> StepReport | None:
        """Return the step that failed, if one did (the robot stops there)."""
        return next((step for step in self.steps if step.status is StepStatus.FAILED), None)

    @property
    def is_stable(self) -> bool:
        return all(check.passed for check in self.stability)

    @property
    def passed(self) -> bool:
        """Return whether every step passed, the assembly held still, and it produces the goal (by motors too)."""
        motors = self.motors is None or (self.motors.failure is None and self.motors.produces_goal)
        return self.failed_step is None and self.is_stable and self.produces_goal and motors

    @property
    def unmet_requirements(self) -> tuple[str, ...]:
        return tuple(requirement.says for requirement in self.requirements if not requirement.met)

    def explanation(self) -> str:
        """Return in one sentence what went wrong (empty when the simulation passed)."""
        problems = []
        failed = self.failed_step
        if failed is not None:
            problems.append(f"step {failed.number} ({failed.text}) failed: {failed.message}")
        if not self.is_stable:
            where = f" (after step {self.unstable_step})" if self.unstable_step else ""
            problems.append("the assembly did not hold still" + where + ": " + self.stability[0].detail)
        if not self.produces_goal:
            problems.append(f"no {self.goal}, because not: " + "; ".join(self.unmet_requirements))
        motors = self.motors
        if motors is not None and motors.failure is not None:
            problems.append(f"driven by its motors, the robot failed at step {motors.step}: {motors.message}")
        elif motors is not None and not motors.produces_goal:
            problems.append(f"driven by its motors, the robot built no {self.goal}")
        return "; ".join(problems)

    def summary(self) -> dict[str, object]:
        """Return the short form a transfer verdict carries."""
        failed = self.failed_step
        return {
            "passed": self.passed,
            "produces_goal": self.produces_goal,
            "stable": self.is_stable,
            "failed_step": failed.number if failed else None,
            "failure": failed.failure.value if failed and failed.failure else None,
            "unmet_requirements": list(self.unmet_requirements),
            "explanation": self.explanation(),
        }

    def as_dict(self) -> dict[str, object]:
        """Return the whole report as a JSON-ready dict (the ``simulate --json`` output)."""
        return {
            "object": self.object_id,
            "passed": self.passed,
            "produces_goal": self.produces_goal,
            "stable": self.is_stable,
            "explanation": self.explanation(),
            "steps": [step.as_dict() for step in self.steps],
            "stability": {
                "checks": [check.as_dict() for check in self.stability],
                "step": self.unstable_step,
            },
            "mechanism": [requirement.as_dict() for requirement in self.requirements],
            "tolerances": dict(self.tolerances),
            "arm": self.arm,
            "timing_ms": {stage: round(seconds * 1000, 2) for stage, seconds in self.timing.items()},
            **({"robot": self._robot_summary()} if self.robot else {}),
        }

    def _robot_summary(self) -> dict[str, object]:
        """Return what the robot did overall: how long its motor commands take, and how its motors did."""
        planned = self.trajectory
        commands = self.motor_commands
        summary: dict[str, object] = {
            "seconds": round(commands.seconds, 2) if commands else 0.0,
            "unconstrained_seconds": round(planned.seconds, 2) if planned else 0.0,
            "rate_hz": planned.rate_hz if planned else None,
            "motions": len(planned.segments) if planned else 0,
        }
        if commands is not None:
            summary["points"] = len(commands.points)
            summary["robot_model"] = commands.limits.model
            summary["safety_factor"] = commands.safety_factor
        if self.motors is not None:
            summary["motors"] = self.motors.as_dict()
        return summary
