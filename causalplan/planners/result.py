"""What a planner returns: a closed status, the steps, the checks made on them, and timings."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

MIN_TIME_LIMIT = 0.001
"""The shortest time limit a request may give (seconds). A millisecond still lets the exact MDP
solve a small object and a known answer come back; below it a limit is a mistake (1e-6, or a
denormal such as 5e-324) and is refused where it is given. The CLI's flag asks for 0.1 at least:
it always starts a planner."""


class PlanStatus(StrEnum):
    """The closed set of planner outcomes; fallbacks and exit codes key on these, never on text."""

    SOLVED = "solved"
    UNSOLVABLE = "unsolvable"
    TIMEOUT = "timeout"
    OUT_OF_MEMORY = "out_of_memory"
    TOO_LARGE = "too_large"  # the exact MDP declined: beyond the size it solves in seconds
    ERROR = "error"

    def is_final(self) -> bool:
        """Return whether the outcome is a definite answer (a plan, or proof that none exists)."""
        return self in (PlanStatus.SOLVED, PlanStatus.UNSOLVABLE)


@dataclass(frozen=True)
class PlanStep:
    """One assembly step: the primitive, its part arguments (moving, fixed), the fit, a sentence."""

    action: str
    args: tuple[str, ...]
    fit: str
    text: str

    def as_dict(self) -> dict[str, object]:
        """Return the step as a JSON-ready dict."""
        return {"action": self.action, "args": list(self.args), "fit": self.fit, "text": self.text}


@dataclass(frozen=True)
class SearchOutcome:
    """The raw outcome of one planner run: status, plan as (action, args) tuples, stage times."""

    status: PlanStatus
    actions: tuple[tuple[str, tuple[str, ...]], ...] = ()
    timing: dict[str, float] = field(default_factory=dict)
    message: str = ""
    success_probability: float | None = None  # set by planners that reason about risk (the MDP)
    expected_actions: float | None = None
    policy: tuple[dict[str, object], ...] = ()
    objective: str | None = None  # the MDP's: "probability" or "attempts"
    optimality: str | None = None  # the MDP's: "optimal" (proved) or "bounded" (the limit came first)
    success_bounds: tuple[float, float] | None = None  # lower and upper bound on the success probability
    required_success: float | None = None
    states: int | None = None  # states the MDP solver stored
    fewest_attempts: bool | None = None  # the MDP's: whether the expected attempts are proved the fewest


@dataclass(frozen=True)
class PlanResult:
    """A plan checked by replay, ready to show: what ``causalplan plan`` prints."""

    status: PlanStatus
    planner_used: str
    object_id: str
    steps: tuple[PlanStep, ...] = ()
    valid_under_model: bool = False
    valid_under_true_mechanism: bool = False
    unmet_requirements: tuple[str, ...] = ()
    timing: dict[str, float] = field(default_factory=dict)
    message: str = ""
    pddl: dict[str, str] | None = None
    success_probability: float | None = None
    expected_actions: float | None = None
    policy: tuple[dict[str, object], ...] = ()
    fallback_reason: str | None = None
    validated_by_up: bool | None = None
    validated_by: dict[str, str] = field(default_factory=dict)
    """Each validator's verdict on the plan: replay always, ``val`` and ``up`` when asked."""
    mdp: dict[str, object] | None = None
    """The MDP's own figures: objective, optimality, success bounds and their gap, states."""

    @property
    def has_plan(self) -> bool:
        return self.status is PlanStatus.SOLVED

    def as_dict(self) -> dict[str, object]:
        """Return the result as a JSON-ready dict (the ``--json`` output)."""
        result: dict[str, object] = {
            "status": self.status.value,
            "planner_used": self.planner_used,
            "object": self.object_id,
            "plan": [step.as_dict() for step in self.steps] if self.has_plan else None,
            "plan_length": len(self.steps) if self.has_plan else None,
            "valid_under_model": self.valid_under_model,
            "valid_under_true_mechanism": self.valid_under_true_mechanism,
            "unmet_requirements": list(self.unmet_requirements),
            "success_probability": None if self.success_probability is None else round(self.success_probability, 6),
            "expected_actions": None if self.expected_actions is None else round(self.expected_actions, 6),
            "fallback_reason": self.fallback_reason,
            "validated_by_up": self.validated_by_up,
            "validated_by": dict(self.validated_by) if self.has_plan else None,
            "timing": {stage: round(seconds, 6) for stage, seconds in self.timing.items()},
            "message": self.message,
        }
        if self.mdp is not None:
            result.update(self.mdp)
        if self.policy:
            result["policy"] = list(self.policy)
        if self.pddl is not None:
            result["pddl"] = self.pddl
        return result
