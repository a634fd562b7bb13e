"""Runs every planner on every task, each run in its own process with a time and memory limit (``processes``).

A run that crashes, is killed at its limit or prints nonsense becomes a row with that status;
it never stops the comparison.
"""

from __future__ import annotations

import json
import statistics
import sys
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass

from causalplan.comparison.tasks import ComparisonTask
from causalplan.comparison.worker import RECORD_FILE
from causalplan.planners import processes

GRACE_SECONDS = 20.0
"""Time a worker gets beyond the planner's limit: its imports, the replay and UP's validator."""


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


def run_once(
    task: ComparisonTask, planner: str, time_limit: float, memory_mb: int, val: bool = False
) -> dict[str, object]:
    """Run one planner on one task in a fresh worker process; return its raw record."""
    request = json.dumps({"task": task.spec, "planner": planner, "time_limit": time_limit, "val": val})
    command = [sys.executable, "-m", "causalplan.comparison.worker"]
    with processes.private_folder("causalplan-compare-") as folder:
        run = processes.run_limited(
            command, folder=folder, time_limit=time_limit + GRACE_SECONDS, memory_mb=memory_mb, stdin=request.encode()
        )
        try:
            record = json.loads((folder / RECORD_FILE).read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError):
            record = None
    if run.timed_out:
        return {"status": "timeout", "message": f"killed after {time_limit + GRACE_SECONDS:g} s"}
    if not isinstance(record, dict):
        tail = run.output.strip().splitlines()[-1:] or [f"exit code {run.returncode}"]
        status = "out_of_memory" if "MemoryError" in tail[0] else "error"
        return {"status": status, "message": f"the worker failed: {tail[0]}"}
    return record


def _is_valid(record: dict[str, object]) -> bool:
    """Return whether every check of a solved run passed: replay, UP's validator, and VAL if it ran."""
    verdicts = record.get("validated_by")
    checked = all(verdict == "valid" for verdict in verdicts.values()) if isinstance(verdicts, dict) else True
    return bool(record.get("valid_under_model")) and record.get("validated_by_up") is not False and checked


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
    rows: list[RunRecord] = []
    for task in tasks:
        for planner in planners:
            records: list[dict[str, object]] = []
            for _ in range(repeat):
                records.append(run_once(task, planner, time_limit, memory_mb, val))
                if progress is not None:
                    progress(f"{planner} on {task.name}")
            rows.append(_summary(task, planner, records))
    return rows


def total_runs(tasks: Iterable[ComparisonTask], planners: list[str], repeat: int) -> int:
    """Return how many worker processes a comparison starts."""
    return len(list(tasks)) * len(planners) * repeat
