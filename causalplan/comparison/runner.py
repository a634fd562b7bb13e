"""Runs every planner on every task, each run in its own process with a time and memory limit.

A run that crashes, is killed at its limit or prints nonsense becomes a row with that status;
it never stops the comparison.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import statistics
import subprocess
import sys
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass

from causalplan.comparison.tasks import ComparisonTask

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


def _limit_memory(megabytes: int) -> Callable[[], None]:
    def apply() -> None:
        limit = megabytes * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    return apply


def run_once(task: ComparisonTask, planner: str, time_limit: float, memory_mb: int) -> dict[str, object]:
    """Run one planner on one task in a fresh worker process; return its raw record."""
    request = json.dumps({"task": task.spec, "planner": planner, "time_limit": time_limit})
    process = subprocess.Popen(
        [sys.executable, "-m", "causalplan.comparison.worker"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
        preexec_fn=_limit_memory(memory_mb),
    )
    try:
        output, errors = process.communicate(request.encode(), timeout=time_limit + GRACE_SECONDS)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
        return {"status": "timeout", "message": f"killed after {time_limit + GRACE_SECONDS:g} s"}
    try:
        record = json.loads(output.decode() or "null")
    except json.JSONDecodeError:
        record = None
    if not isinstance(record, dict):
        tail = errors.decode(errors="replace").strip().splitlines()[-1:] or [f"exit code {process.returncode}"]
        status = "out_of_memory" if "MemoryError" in tail[0] else "error"
        return {"status": status, "message": f"the worker failed: {tail[0]}"}
    return record


def _summary(task: ComparisonTask, planner: str, records: list[dict[str, object]]) -> RunRecord:
    statuses = Counter(str(record.get("status")) for record in records)
    status = statuses.most_common(1)[0][0]
    same = [record for record in records if record.get("status") == status]
    first = same[0]
    times = [float(str(record["seconds"])) for record in same if record.get("seconds") is not None]
    valid: bool | None = None
    if status == "solved":
        valid = all(bool(r.get("valid_under_model")) and r.get("validated_by_up") is not False for r in same)
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
) -> list[RunRecord]:
    """Run every planner on every task ``repeat`` times; return one median record per pair."""
    rows: list[RunRecord] = []
    for task in tasks:
        for planner in planners:
            records: list[dict[str, object]] = []
            for _ in range(repeat):
                records.append(run_once(task, planner, time_limit, memory_mb))
                if progress is not None:
                    progress(f"{planner} on {task.name}")
            rows.append(_summary(task, planner, records))
    return rows


def total_runs(tasks: Iterable[ComparisonTask], planners: list[str], repeat: int) -> int:
    """Return how many worker processes a comparison starts."""
    return len(list(tasks)) * len(planners) * repeat
