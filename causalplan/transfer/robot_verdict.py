"""The robot's word on a plan, for callers above the simulator: transfer verdicts and the web service.

``robot_run(obj, steps)`` is the Panda's run of a plan, kept per object and steps;
``robot_transfer_verdict(...)`` is ``transfer_verdict`` with the robot as the last judge: a plan
that transfers on paper and in physics but that the robot cannot carry out fails with the reason
``robot_cannot_execute``, naming the step and the code. Films of the robot are made by the
service's work layer (``service.work.robot``) and the CLI's ``simulate --robot --video``.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from causalplan import caches
from causalplan.caches import BoundedCache
from causalplan.causal.diagnostics import Severity
from causalplan.objects.model import AssemblyObject
from causalplan.planners.fd import DEFAULT_TIME_LIMIT
from causalplan.planners.result import PlanStep
from causalplan.sim.executor import simulate_plan
from causalplan.sim.outcomes import RenderMode
from causalplan.sim.plan_steps import StepRequest, check_steps
from causalplan.sim.report import SimulationReport
from causalplan.transfer.verdict import Reason, TransferVerdict, Verdict, transfer_verdict

if TYPE_CHECKING:
    from causalplan.inputs import LoadedMapping, LoadedModel
    from causalplan.objects.catalog import Catalog

ROBOT_CANNOT_EXECUTE = "robot_cannot_execute"


def robot_run(obj: AssemblyObject, steps: Sequence[PlanStep | StepRequest], motors: bool = False) -> SimulationReport:
    """Return the robot's run of ``steps`` on ``obj``, without pictures; ``motors``: driven by its motors too.

    Deterministic, so kept (the process's ``robot_runs`` cache) by the object and the checked
    steps: a batch judges the same plan on the same object many times, and a planner's step
    and the request for it are one step. PlanInputError for steps that do not belong to ``obj``.
    """
    checked = check_steps(steps, obj)
    runs: BoundedCache[tuple[Hashable, ...], SimulationReport] = caches.current().robot_runs
    return runs.get_or_make(
        (obj, checked, motors),
        lambda: simulate_plan(obj, checked, render=RenderMode.NONE, robot=True, motors=motors),
    )


def robot_reason(report: SimulationReport) -> Reason | None:
    """Return why the robot could not carry out the plan of ``report`` (None when it could)."""
    failed = report.failed_step
    if failed is None and report.produces_goal:  # as planned; then by its motors, when they drove it
        motors = report.motors
        if motors is None or (motors.failure is None and motors.produces_goal):
            return None
        if motors.failure is None:
            message = f"Driven by its motors, the robot carried out every step, but built no {report.goal}."
            return Reason(ROBOT_CANNOT_EXECUTE, Severity.ERROR, message, ("motors",))
        code = motors.failure.value
        message = f"Driven by its motors, the robot cannot carry out step {motors.step}: {code}: {motors.message}."
        return Reason(ROBOT_CANNOT_EXECUTE, Severity.ERROR, message, (f"step {motors.step}", code))
    if failed is None:
        message = f"The robot carried out every step, but {report.explanation()}."
        return Reason(ROBOT_CANNOT_EXECUTE, Severity.ERROR, message, report.unmet_requirements)
    code = failed.failure.value if failed.failure else "failed"
    message = f"The robot cannot carry out step {failed.number} ({failed.text}): {code}: {failed.message}."
    return Reason(ROBOT_CANNOT_EXECUTE, Severity.ERROR, message, (f"step {failed.number}", code))


def robot_transfer_verdict(
    loaded_model: LoadedModel,
    loaded_mapping: LoadedMapping,
    catalog: Catalog,
    planner: str = "auto",
    time_limit: float = DEFAULT_TIME_LIMIT,
) -> TransferVerdict:
    """Return ``transfer_verdict`` with the robot as the last judge (``decided_by`` "robot" when it fails)."""
    return robot_judged(transfer_verdict(loaded_model, loaded_mapping, catalog, planner, time_limit), catalog)


def robot_judged(verdict: TransferVerdict, catalog: Catalog) -> TransferVerdict:
    """Return ``verdict`` with the robot as the last judge: a transfer it cannot carry out fails (by "robot").

    Other verdicts are returned as they are: the robot only judges plans that transfer.
    """
    if verdict.verdict is not Verdict.TRANSFERS or verdict.plan is None or verdict.test_object is None:
        return verdict
    report = robot_run(catalog.get(verdict.test_object), tuple(verdict.plan.steps))
    reason = robot_reason(report)
    if reason is None:
        return replace(verdict, simulation=report)
    return replace(
        verdict, verdict=Verdict.FAILS, decided_by="robot", reasons=(*verdict.reasons, reason), simulation=report
    )
