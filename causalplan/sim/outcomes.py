"""The records a simulation is made of: failure codes, checks, steps, requirements, pictures.

They sit below every simulator module (the robot's included); ``report`` assembles them.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from PIL import Image


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
    """Why the robot could not do a motion: the failure code and the check that says so.

    ``obstacle``: when no arm pose can go on along a line without touching something, the
    body (a part's id, or the table) that the best of them touched.
    """

    failure: Failure
    check: Check
    obstacle: str | None = None


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
