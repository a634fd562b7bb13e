"""What a simulation reports: per step, its checks and any failure; then stability and the mechanism."""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from PIL import Image

    from causalplan.sim.poses import Pose
    from causalplan.sim.robot.motors import MotorRun
    from causalplan.sim.robot.trajectory import Trajectory, Waypoints


class RenderMode(StrEnum):
    """Which pictures a simulation draws."""

    NONE = "none"
    FINAL = "final"  # one picture of the final assembly
    FRAMES = "frames"  # the start, one picture after each step, and the final assembly


class StepStatus(StrEnum):
    PASSED = "passed"
    FAILED = "failed"
    NOT_RUN = "not_run"  # an earlier step failed, so the robot stopped


class Failure(StrEnum):
    """Why a step failed: a closed set, stable for programs to match on."""

    INCOMPATIBLE_CONNECTORS = "incompatible_connectors"  # no free pair of connectors with the same spec
    MISSING_PART = "missing_part"  # the part to attach to is not in the assembly
    ALREADY_ATTACHED = "already_attached"  # the part to attach is already in the assembly
    BLOCKED_PATH = "blocked_path"  # another part is in the way of the approach
    NO_CONTACT = "no_contact"  # at its seat the part does not touch the part it joins
    MISALIGNED = "misaligned"  # the joined connectors are further apart (or more tilted) than allowed
    FALLS = "falls"  # a part moved or tilted while the assembly settled
    UNREACHABLE = "unreachable"  # the robot: no IK solution for a grasp, approach or seat pose
    NO_COLLISION_FREE_PATH = "no_collision_free_path"  # the robot: the motion planner found no path
    COLLISION = "collision"  # the robot: an executed motion touched what it must not
    GRASP_LOST = "grasp_lost"  # the robot: the part moved in the gripper beyond tolerance
    LIMIT_VIOLATION = "limit_violation"  # the robot: a motor command beyond its datasheet limits
    TRACKING_ERROR = "tracking_error"  # the robot's motors: the arm did not follow its commands
    GRASP_SLIPPED = "grasp_slipped"  # the robot's motors: a held part slipped in (or out of) the gripper


@dataclass(frozen=True)
class Check:
    """One check: its name, whether it passed, and the measured figure against its tolerance."""

    name: str
    passed: bool
    detail: str
    measured: float | None = None
    tolerance: float | None = None
    unit: str = ""

    def as_dict(self) -> dict[str, object]:
        """Return the check as a JSON-ready dict."""
        return {
            "name": self.name,
            "passed": self.passed,
            "measured": self.measured,
            "tolerance": self.tolerance,
            "unit": self.unit,
            "detail": self.detail,
        }


@dataclass(frozen=True)
class RobotFailure:
    """Why the robot could not do a motion: the failure code and the check that says so."""

    failure: Failure
    check: Check


@dataclass(frozen=True)
class Reach:
    """Whether the robot arm reaches a step's grasp poses (approach start and seat) by inverse kinematics."""

    reachable: bool
    error_mm: float

    def as_dict(self) -> dict[str, object]:
        return {"reachable": self.reachable, "error_mm": round(self.error_mm, 2)}


@dataclass(frozen=True)
class StepReport:
    """One executed (or skipped) step of the plan."""

    number: int
    action: str
    moving: str
    fixed: str
    fit: str | None
    text: str
    status: StepStatus
    checks: tuple[Check, ...] = ()
    failure: Failure | None = None
    message: str = ""
    reach: Reach | None = None
    motions: tuple[str, ...] = ()
    """What the robot did in this step (``robot`` runs only): transit, grasp, carry, ..."""

    def as_dict(self) -> dict[str, object]:
        """Return the step as a JSON-ready dict."""
        result: dict[str, object] = {
            "number": self.number,
            "action": self.action,
            "args": [self.moving, self.fixed],
            "fit": self.fit,
            "text": self.text,
            "status": self.status.value,
            "failure": self.failure.value if self.failure else None,
            "message": self.message,
            "checks": [check.as_dict() for check in self.checks],
        }
        if self.reach is not None:
            result["reach"] = self.reach.as_dict()
        if self.motions:
            result["robot"] = list(self.motions)
        return result


@dataclass(frozen=True)
class RequirementCheck:
    """One requirement of the object's true mechanism, judged on the simulated assembly."""

    says: str
    met: bool
    fit: str | None
    detail: str

    def as_dict(self) -> dict[str, object]:
        return {"says": self.says, "met": self.met, "fit": self.fit, "detail": self.detail}


@dataclass(frozen=True)
class Picture:
    """An RGB picture, row by row, three bytes a pixel."""

    width: int
    height: int
    rgb: bytes

    def image(self) -> Image.Image:
        """Return the picture as a Pillow image."""
        from PIL import Image

        return Image.frombytes("RGB", (self.width, self.height), self.rgb)

    def png(self) -> bytes:
        """Return the picture encoded as PNG."""
        buffer = io.BytesIO()
        self.image().save(buffer, format="PNG", optimize=False)
        return buffer.getvalue()


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
            "unconstrained_seconds": round(sum(len(s.positions) for s in planned.segments) / planned.rate_hz, 2)
            if planned
            else 0.0,
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
