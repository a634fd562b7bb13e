"""Transfer verdicts: plan a model on a new object through a person's step-3 mapping, and say why.

A model transfers when, using only the mapping of the new object's parts to the model's
functions, the planner finds a plan *and* that plan makes the real object work (its true
mechanism). Every failure names its reasons, as the paper's authors did by hand. What can be
decided without the planner (an invalid model, a function the goal needs that no part
carries) is decided without it, and the verdict says so in ``decided_by``.
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import asdict, dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING

from causalplan import caches
from causalplan.caches import BoundedCache
from causalplan.causal.diagnostics import Report, Severity
from causalplan.causal.graph import goal_holds
from causalplan.causal.model import CausalModel, Labelling
from causalplan.objects.catalog import Catalog
from causalplan.objects.model import AssemblyObject
from causalplan.pddl.task import build_task
from causalplan.planners.fd import DEFAULT_TIME_LIMIT
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanResult, PlanStatus, PlanStep
from causalplan.transfer.generalization import near_or_far

if TYPE_CHECKING:
    from causalplan.inputs import LoadedMapping, LoadedModel
    from causalplan.sim import SimulationReport


class Verdict(StrEnum):
    """The outcome of a transfer trial."""

    TRANSFERS = "transfers"
    FAILS = "fails"
    INVALID = "invalid"
    UNDECIDED = "undecided"  # the planner timed out or failed: neither success nor failure is shown

    @property
    def exit_code(self) -> int:
        return {"transfers": 0, "fails": 1, "invalid": 2, "undecided": 3}[self.value]


@dataclass(frozen=True)
class Reason:
    """One reason for a verdict: a stable code, a severity, plain words, the labels involved."""

    code: str
    severity: Severity
    message: str
    labels: tuple[str, ...] = ()

    def as_dict(self) -> dict[str, object]:
        """Return the reason as a JSON-ready dict."""
        return {**asdict(self), "severity": self.severity.value, "labels": list(self.labels)}


@dataclass(frozen=True)
class TransferVerdict:
    """What ``causalplan transfer`` reports."""

    verdict: Verdict
    training_object: str | None
    test_object: str | None
    generalization: str | None
    decided_by: str
    reasons: tuple[Reason, ...] = ()
    plan: PlanResult | None = None
    diagnostics: dict[str, object] = field(default_factory=dict)
    simulation: SimulationReport | None = None  # the plan run in physics, when it was

    def as_dict(self) -> dict[str, object]:
        """Return the verdict as a JSON-ready dict (the ``--json`` output)."""
        plan = self.plan
        return {
            "verdict": self.verdict.value,
            "training_object": self.training_object,
            "test_object": self.test_object,
            "generalization": self.generalization,
            "decided_by": self.decided_by,
            "reasons": [reason.as_dict() for reason in self.reasons],
            "plan": [step.as_dict() for step in plan.steps] if plan and plan.has_plan else None,
            "planning": plan.as_dict() if plan else None,
            "diagnostics": self.diagnostics,
            "simulation": self.simulation.summary() if self.simulation else None,
        }


def generalization(training: AssemblyObject, test: AssemblyObject) -> str:
    """Return ``near`` (same category), ``far`` (other category) or ``same_object``."""
    if training.id == test.id:
        return "same_object"
    return near_or_far([training.category], test.category)


def invalid_verdict(
    model_report: Report, mapping_report: Report, training: str | None, test: str | None
) -> TransferVerdict:
    """Return the verdict for a model or mapping that did not validate."""
    reasons = [
        Reason("invalid_model", Severity.ERROR, _located(d.message, d.location.describe())) for d in model_report.errors
    ]
    reasons += [
        Reason("invalid_mapping", Severity.ERROR, _located(d.message, d.location.describe()))
        for d in mapping_report.errors
    ]
    return TransferVerdict(
        Verdict.INVALID,
        training,
        test,
        None,
        "validation",
        tuple(reasons),
        diagnostics={"model": model_report.as_dict(), "mapping": mapping_report.as_dict()},
    )


def _located(message: str, where: str) -> str:
    return f"{message} ({where})" if where else message


def needed_functions(model: CausalModel) -> dict[str, str]:
    """Return the model's function nodes: causes that no rule produces, with their labels."""
    effects = {rule.effect_key for rule in model.rules}
    labels = model.node_labels()
    return {key: labels[key] for rule in model.rules for key in sorted(rule.cause_keys) if key not in effects}


def _mapping_reasons(model: CausalModel, mapping: Labelling, test: AssemblyObject) -> tuple[list[Reason], bool]:
    """Return the reasons visible from the mapping alone, and whether the goal is still reachable."""
    carriers = mapping.carriers()
    reachable = goal_holds(carriers, model.rules, model.goal_key)
    reasons: list[Reason] = []
    for key, label in needed_functions(model).items():
        if key in carriers:
            continue
        # A missing function is fatal only when no other rule can still produce the goal.
        severity = Severity.WARNING if reachable else Severity.ERROR
        consequence = (
            f"; the model can still produce {model.goal} through another rule."
            if reachable
            else f", which the model needs for {model.goal}."
        )
        message = f"No part of the {test.name} carries '{label}'{consequence}"
        reasons.append(Reason("missing_function", severity, message, (label,)))
    used = model.used_labels()
    mapped_labels = mapping.labels()
    for key, parts in carriers.items():
        if key not in used:
            reasons.append(
                Reason(
                    "unmodelled_function",
                    Severity.WARNING,
                    f"'{mapped_labels[key]}' (given to {', '.join(parts)}) is not in the model: no rule "
                    f"uses it, so it cannot help produce {model.goal}.",
                    (mapped_labels[key],),
                )
            )
    return reasons, reachable


def transfer_verdict(
    loaded_model: LoadedModel,
    loaded_mapping: LoadedMapping,
    catalog: Catalog,
    planner: str = "auto",
    time_limit: float = DEFAULT_TIME_LIMIT,
    simulate: bool = True,
    val: bool = False,
) -> TransferVerdict:
    """Return the verdict of a model and a mapping as read: ``invalid`` unless both validated.

    ``val`` checks the plan with VAL too (see ``plan_task``).
    """
    if loaded_model.is_valid and loaded_mapping.is_valid:
        assert loaded_model.model is not None and loaded_mapping.mapping is not None
        return evaluate_transfer(
            loaded_model.model, loaded_mapping.mapping, catalog, planner, time_limit, simulate, val=val
        )
    return invalid_verdict(
        loaded_model.report,
        loaded_mapping.report,
        loaded_model.model.object_id if loaded_model.model else None,
        loaded_mapping.mapping.object_id if loaded_mapping.mapping else None,
    )


def _simulated(obj: AssemblyObject, steps: tuple[PlanStep, ...]) -> SimulationReport:
    """Return the simulator's report of ``steps`` on ``obj`` (deterministic, so kept by object and checked steps)."""
    from causalplan.sim import RenderMode, simulate_plan  # PyBullet loads only when a plan is simulated
    from causalplan.sim.plan_steps import check_steps

    kept: BoundedCache[tuple[Hashable, ...], SimulationReport] = caches.current().simulations
    checked = check_steps(steps, obj)
    return kept.get_or_make((obj, checked), lambda: simulate_plan(obj, checked, render=RenderMode.NONE))


def evaluate_transfer(
    model: CausalModel,
    mapping: Labelling,
    catalog: Catalog,
    planner: str = "auto",
    time_limit: float = DEFAULT_TIME_LIMIT,
    simulate: bool = True,
    val: bool = False,
) -> TransferVerdict:
    """Return the verdict of trying a valid ``model`` on the object of a valid ``mapping``.

    A plan that replay finds valid under the true mechanism (the fast pre-check) is then run
    in the physics simulator, unless ``simulate`` is False, and the simulator has the last word.
    ``val`` checks the plan with VAL too; a plan VAL rejects raises ``PlanRejectedError``.
    """
    training, test = catalog.get(model.object_id), catalog.get(mapping.object_id)
    kind = generalization(training, test)
    reasons, reachable = _mapping_reasons(model, mapping, test)
    if not reachable:
        return TransferVerdict(Verdict.FAILS, training.id, test.id, kind, "precheck", tuple(reasons))
    result = plan_task(build_task(model, test, mapping), planner, time_limit, val=val)
    if result.status is PlanStatus.SOLVED and result.valid_under_true_mechanism:
        simulation = _simulated(test, result.steps) if simulate else None
        if simulation is None or simulation.produces_goal:
            return TransferVerdict(
                Verdict.TRANSFERS, training.id, test.id, kind, "planner", tuple(reasons), result, simulation=simulation
            )
        reasons.append(
            Reason(
                "violates_true_mechanism",
                Severity.ERROR,
                f"The plan satisfies the model and, step by step, the {test.name}'s requirements, but in "
                f"simulation the real {test.name} does not produce {test.goal}: {simulation.explanation()}.",
                simulation.unmet_requirements,
            )
        )
        return TransferVerdict(
            Verdict.FAILS, training.id, test.id, kind, "simulator", tuple(reasons), result, simulation=simulation
        )
    verdict = Verdict.FAILS
    if result.status is PlanStatus.SOLVED:
        reason = Reason(
            "violates_true_mechanism",
            Severity.ERROR,
            f"The plan satisfies the model, but the real {test.name} would not produce {test.goal}; "
            f"it also needs: {'; '.join(result.unmet_requirements)}.",
            result.unmet_requirements,
        )
    elif result.status is PlanStatus.UNSOLVABLE:
        reason = Reason(
            "no_assembly_sequence",
            Severity.ERROR,
            f"Every function the model needs is carried by some part, but no order of connecting "
            f"the {test.name}'s parts brings them together.",
        )
    else:
        verdict = Verdict.UNDECIDED
        reason = Reason(
            "planner_error", Severity.ERROR, f"The planner could not decide ({result.status.value}): {result.message}"
        )
    reasons.append(reason)
    return TransferVerdict(verdict, training.id, test.id, kind, "planner", tuple(reasons), result)
