"""Runs every planner on every task, each run in a process of its own with a time and memory limit.

Each run is forked from a warm parent: multiprocessing's fork server, which has preloaded the
planners, FD's translator and the MDP (``PRELOADED``), so a run (``worker``) starts with
nothing left to import and no state of an earlier run; it sends its record through a pipe and
is killed at its limit (by hand: ``pebble``'s wait for a finished process was slower than the
paper's tasks take to plan; benchmarks/RESULTS.md). A run that crashes, is killed at its
limit or runs out of memory becomes a row with that status; it never stops the comparison.
Plans are checked by replay inside the run and by VAL here in the parent (each distinct plan
of a task once), outside the timed part.
"""

from __future__ import annotations

import multiprocessing
import statistics
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass
from multiprocessing import forkserver
from multiprocessing.context import ForkServerContext
from pathlib import Path

from causalplan.comparison import worker
from causalplan.comparison.tasks import ComparisonTask, build
from causalplan.pddl.task import PlanningTask
from causalplan.pddl.writer import CompiledTask, compile_task
from causalplan.planners import processes
from causalplan.planners.val import ValVerdict, validate

GRACE_SECONDS = 20.0
"""Time a run gets beyond the planner's limit: its replay, and for ``up:`` planners loading unified-planning."""

PRELOADED = (
    "__main__",
    "causalplan.comparison.worker",
    "causalplan.planners.pipeline",
    "causalplan.planners.mdp",
    "fast_downward.translate.main",
)
"""What the fork server imports once for every run: the planners, FD's translator (it runs in the
run's process), and ``__main__`` (or each run would import it again)."""


@dataclass(frozen=True)
class RunRecord:
    """One planner on one task (the median over repeats): a row of the comparison."""

    task: str
    parts: int
    planner: str
    status: str
    planner_used: str | None
    plan_length: int | None
    seconds: float | None
    success_probability: float | None
    valid: bool | None
    repeats: int
    message: str

    def as_dict(self) -> dict[str, object]:
        """Return the record as a JSON-ready dict."""
        return asdict(self)


def fork_server(planners: Iterable[str] = ()) -> ForkServerContext:
    """Return the fork server's context, set to preload what runs of ``planners`` import.

    The server starts at this process's first call and the preload counts only then; it is
    what makes runs start warm, never what makes them right.
    """
    context = multiprocessing.get_context("forkserver")
    modules = [*PRELOADED]
    if any(planner.startswith("up:") for planner in planners):
        modules.append("causalplan.planners.up_problem")
    context.set_forkserver_preload(modules)
    forkserver.ensure_running()  # it preloads while this process goes on (with the first run, it would wait)
    return context


def _died(folder: Path, exitcode: int | None) -> dict[str, object]:
    """Return the record of a run whose process ended without a record (its output's last line says why)."""
    tail = processes.output_in(folder).strip().splitlines()[-1:] or [f"exit code {exitcode}"]
    status = "out_of_memory" if "MemoryError" in tail[0] else "error"
    return {"status": status, "message": f"the worker failed: {tail[0]}"}


def _run(
    task: PlanningTask, planner: str, time_limit: float, memory_mb: int, context: ForkServerContext
) -> dict[str, object]:
    """Run one planner on one task in a new process forked from the fork server; return its raw record."""
    limit = time_limit + GRACE_SECONDS
    with processes.private_folder("causalplan-compare-") as folder:
        answers, answer = context.Pipe(duplex=False)
        process = context.Process(
            target=worker.serve, args=(answer, task, planner, time_limit, memory_mb, folder), daemon=True
        )
        process.start()
        answer.close()  # the run holds the only sending end: its death ends the wait below
        try:
            if not answers.poll(limit):
                return {"status": "timeout", "message": f"killed after {limit:g} s"}
            record: dict[str, object] = answers.recv()
        except EOFError:
            process.join()
            return _died(folder, process.exitcode)
        finally:
            if process.is_alive():
                process.kill()
            process.join()
            answers.close()
    return record


def _checked_by_val(readable: CompiledTask, record: dict[str, object]) -> dict[str, object]:
    """Return ``record`` with VAL's verdict on its plan for the ``readable`` PDDL (VAL runs once per distinct plan)."""
    actions = record.get("actions")
    verdicts = record.get("validated_by")
    if not isinstance(actions, list) or not isinstance(verdicts, dict):
        return record
    report = validate(readable.domain, readable.problem, [(action, tuple(args)) for action, args in actions])
    message = record.get("message") or ("" if report.verdict is ValVerdict.VALID else report.words)
    return {**record, "validated_by": {**verdicts, "val": report.verdict.value}, "message": message}


def _readable(task: PlanningTask, val: bool) -> CompiledTask | None:
    """Return the PDDL VAL checks a task's plans on (the person's rules as written: one derived clause per rule)."""
    return compile_task(task) if val else None


def _record(
    task: PlanningTask,
    planner: str,
    time_limit: float,
    memory_mb: int,
    readable: CompiledTask | None,
    context: ForkServerContext,
) -> dict[str, object]:
    """Run one planner on one task; VAL checks its plan on ``readable`` (None: no VAL)."""
    record = _run(task, planner, time_limit, memory_mb, context)
    return record if readable is None else _checked_by_val(readable, record)


def run_once(
    task: ComparisonTask, planner: str, time_limit: float, memory_mb: int, val: bool = False
) -> dict[str, object]:
    """Run one planner on one task in a process of its own; return its raw record (``val``: VAL checks the plan)."""
    built = build(task.spec)
    return _record(built, planner, time_limit, memory_mb, _readable(built, val), fork_server([planner]))


def _is_valid(record: dict[str, object]) -> bool:
    """Return whether every check of a solved run passed: replay, VAL if it ran, UP's validator for ``up:`` runs."""
    verdicts = record.get("validated_by")
    checked = all(verdict == "valid" for verdict in verdicts.values()) if isinstance(verdicts, dict) else False
    return bool(record.get("valid_under_model")) and checked


def _summary(task: ComparisonTask, planner: str, records: list[dict[str, object]]) -> RunRecord:
    statuses = Counter(str(record.get("status")) for record in records)
    status = statuses.most_common(1)[0][0]
    same = [record for record in records if record.get("status") == status]
    first = same[0]
    times = [float(str(record["seconds"])) for record in same if record.get("seconds") is not None]
    valid: bool | None = None
    if status == "solved":
        valid = all(_is_valid(record) for record in same)
    length = first.get("plan_length")
    probability = first.get("success_probability")
    return RunRecord(
        task=task.name,
        parts=task.parts,
        planner=planner,
        status=status,
        planner_used=str(first["planner_used"]) if first.get("planner_used") else None,
        plan_length=int(str(length)) if length is not None else None,
        seconds=statistics.median(times) if times else None,
        success_probability=float(str(probability)) if probability is not None else None,
        valid=valid,
        repeats=len(records),
        message=str(first.get("message") or ""),
    )


def compare(
    tasks: list[ComparisonTask],
    planners: list[str],
    time_limit: float,
    memory_mb: int,
    repeat: int,
    progress: Callable[[str], None] | None = None,
    val: bool = False,
) -> list[RunRecord]:
    """Run every planner on every task ``repeat`` times; return one median record per pair.

    ``val`` has VAL check every plan too (outside the timed part of each run).
    """
    context = fork_server(planners)
    rows: list[RunRecord] = []
    for task in tasks:
        built = build(task.spec)
        readable = _readable(built, val)  # compiled once for every run of the task
        for planner in planners:
            records: list[dict[str, object]] = []
            for _ in range(repeat):
                records.append(_record(built, planner, time_limit, memory_mb, readable, context))
                if progress is not None:
                    progress(f"{planner} on {task.name}")
            rows.append(_summary(task, planner, records))
    return rows


def total_runs(tasks: Iterable[ComparisonTask], planners: list[str], repeat: int) -> int:
    """Return how many runs (each a process of its own) a comparison makes."""
    return len(list(tasks)) * len(planners) * repeat
