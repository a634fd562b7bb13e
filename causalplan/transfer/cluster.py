"""A batch of trials judged on a Dask distributed cluster: a scheduler's address, or a local one.

Trials go in chunks, not one task each: a trial takes a few milliseconds and Dask's own
overhead is near a millisecond a task, so one task per trial would spend most of the time on
scheduling. The catalog is sent to every worker once (``scatter(..., broadcast=True)``), each
chunk is ``run_batch`` on a worker (so its caches work within the chunk and across the chunks
that worker gets), and the chunks' results come back as they finish. A worker that dies in
the middle of a chunk has that chunk run again elsewhere, which Dask does on its own (its
``allowed-failures`` setting); the chunk's future then holds exactly one result, so nothing is
lost or counted twice. The verdicts are those of the local batch, in the trials' order.

Two ways in. ``run_batch_on_cluster`` takes trials and gives back whole ``TrialResult``s.
``write_batch_on_cluster`` is the ``batch`` command's way and the cheaper one: the client only
reads the file's raw lines (``file_chunks``), the workers parse them, judge them and send back
each trial's CSV row and JSON line (``WrittenResult``), which the client writes as they are.
Whole verdicts are thousands of small objects each, slow to pickle on a worker and slower to
unpickle in the client; the client shares the cores with the workers, so what it does not do
the workers get to do. Every task's result comes back in a box (``Boxed``), one pickle.
"""

from __future__ import annotations

import logging
import multiprocessing
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from causalplan.errors import CausalPlanError
from causalplan.objects.catalog import Catalog
from causalplan.transfer.batch import (
    Judge,
    Trial,
    TrialResult,
    WrittenResult,
    is_blank_line,
    read_trials,
    run_batch,
    trials_of_lines,
)

if TYPE_CHECKING:
    from distributed import Client

DEFAULT_CHUNK_SIZE = 250
CONNECT_TIMEOUT = "10s"
LOCAL_CLUSTER_SETTINGS = {
    "distributed.admin.tick.interval": "1s",  # the event loops' health check, far more often by default
    "distributed.worker.profile.enabled": False,  # samples every task's stack for a dashboard we do not start
    "distributed.worker.memory.monitor-interval": "1s",  # a batch's memory grows slowly
    "distributed.admin.system-monitor.interval": "2s",  # CPU and network statistics for the dashboard
}
"""Dask settings of a local cluster (``--workers``): its own housekeeping, at Dask's defaults, keeps
the client's process and every worker busy even when idle, on the same cores the trials need."""


class ClusterError(CausalPlanError):
    """The Dask cluster could not be reached or started, or a chunk failed there for good."""

    code = "cluster_error"


@dataclass(frozen=True)
class JudgeOptions:
    """How every trial is judged: the same on every worker."""

    planner: str = "auto"
    time_limit: float = 30.0
    simulate: bool = True
    val: bool = False
    judge: Judge | None = None
    """The last judge of each verdict (e.g. ``transfer.robot_verdict.robot_judged``): a top-level function,
    so it travels to the workers by name."""


def judge_chunk(trials: list[Trial], catalog: Catalog, options: JudgeOptions) -> list[TrialResult]:
    """Return the results of one chunk of trials (the task a worker runs)."""
    return run_batch(
        trials, catalog, options.planner, options.time_limit, options.simulate, val=options.val, judge=options.judge
    )


@dataclass(frozen=True)
class NumberedLines:
    """Consecutive raw lines of a JSON Lines batch file from ``first_line`` on: a chunk the worker parses."""

    first_line: int
    lines: list[bytes]
    trial_count: int
    """How many of the lines are trials (the others are blank)."""

    def trials(self) -> list[Trial]:
        """Return the chunk's trials, read exactly as ``read_trials`` reads the file."""
        return list(trials_of_lines(enumerate(self.lines, start=self.first_line)))


TrialChunk = list[Trial] | NumberedLines
"""What one task judges: trials already read, or raw lines of a JSON Lines file."""


def write_chunk(chunk: TrialChunk, catalog: Catalog, options: JudgeOptions) -> list[WrittenResult]:
    """Return one chunk's results as the batch files hold them (the task a worker runs for ``batch``)."""
    trials = chunk.trials() if isinstance(chunk, NumberedLines) else chunk
    return [result.written() for result in judge_chunk(trials, catalog, options)]


def chunks(trials: Sequence[Trial], size: int) -> list[list[Trial]]:
    """Return the trials cut into consecutive chunks of ``size`` (the last may be shorter)."""
    return [list(trials[start : start + size]) for start in range(0, len(trials), size)]


def file_chunks(path: Path, size: int) -> list[TrialChunk]:
    """Return a batch file cut into chunks of ``size`` trials, in the file's order.

    A JSON Lines file is cut into raw lines, left for the workers to parse; any other file (or
    one that cannot be opened, which ``read_trials`` turns into an unreadable trial) is read here.
    """
    if size < 1:
        raise ClusterError(f"The chunk size must be at least 1; got {size}.")
    if path.suffix.lower() == ".jsonl":
        try:
            with path.open("rb") as handle:
                lines = list(handle)  # split as read_trials splits the file: at b"\n" only
        except OSError:
            pass
        else:
            return [
                NumberedLines(start + 1, part, sum(not is_blank_line(line) for line in part))
                for start in range(0, len(lines), size)
                if (part := lines[start : start + size])
            ]
    return list(chunks(list(read_trials(path)), size))  # a list of TrialChunk, not of list[Trial]


def trials_in(parts: Sequence[TrialChunk]) -> int:
    """Return how many trials the chunks hold."""
    return sum(part.trial_count if isinstance(part, NumberedLines) else len(part) for part in parts)


def connect(address: str | None, workers: int | None) -> tuple[Client, Any]:
    """Return a client of the cluster at ``address``, or of a new local cluster of ``workers`` processes.

    The second value is the local cluster to close after the client (None for a remote one).
    """
    import dask
    from distributed import Client, LocalCluster

    if address is not None:
        try:
            return Client(address, timeout=CONNECT_TIMEOUT), None
        except (OSError, TimeoutError) as exc:
            raise ClusterError(
                f"Cannot reach the Dask scheduler at {address}: {exc}. Is `dask scheduler` running there?",
                details={"address": address},
            ) from exc
    settings = {**LOCAL_CLUSTER_SETTINGS, "distributed.worker.multiprocessing-method": _local_start_method()}
    with dask.config.set(settings):  # read when the scheduler, nannies, workers and client start
        cluster = LocalCluster(
            n_workers=workers or 1,
            threads_per_worker=1,  # the planners keep per-process state; one trial at a time per process
            processes=True,
            dashboard_address=None,
            # Without a dashboard the scheduler still serves its HTTP routes, on port 8787 by default:
            # a free port instead, so a second cluster at once starts without a warning.
            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
            silence_logs=logging.ERROR,
        )
        return Client(cluster), cluster


def _local_start_method() -> str:
    """Return how a local cluster starts its worker processes: ``fork`` where there is one.

    A forked worker starts with this process's modules already imported (Dask's default,
    ``spawn``, starts a fresh interpreter that imports Dask and then causalplan again), which
    on a busy machine is seconds per worker. A worker the nanny restarts later (after a
    crash) is spawned, Dask's default: that only costs time.
    """
    return "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"


def run_batch_on_cluster(
    trials: Sequence[Trial],
    catalog: Catalog,
    options: JudgeOptions = JudgeOptions(),
    *,
    address: str | None = None,
    workers: int | None = None,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
    on_chunk: Callable[[list[TrialResult]], None] | None = None,
) -> list[TrialResult]:
    """Return the results of every trial, in order, judged on a Dask cluster.

    ``on_chunk`` is called with each chunk's results as soon as it is done (in the order the
    chunks finish), so a caller can write them out and show progress as they come.
    """
    if chunk_size < 1:
        raise ClusterError(f"The chunk size must be at least 1; got {chunk_size}.")
    return _judge_on_cluster(judge_chunk, chunks(trials, chunk_size), catalog, options, address, workers, on_chunk)


def write_batch_on_cluster(
    parts: Sequence[TrialChunk],
    catalog: Catalog,
    options: JudgeOptions = JudgeOptions(),
    *,
    address: str | None = None,
    workers: int | None = None,
    on_chunk: Callable[[list[WrittenResult]], None] | None = None,
) -> list[WrittenResult]:
    """Return the CSV row and JSON line of every trial of the chunks (e.g. ``file_chunks``), in order.

    ``on_chunk`` is called as in ``run_batch_on_cluster``.
    """
    return _judge_on_cluster(write_chunk, list(parts), catalog, options, address, workers, on_chunk)


Result = TypeVar("Result")


@dataclass(frozen=True)
class Boxed:
    """A task's result as it travels back: Dask serializes a list or a tuple item by item, a frame
    for each (thousands for a chunk's results, each framed, sent and read on its own), a box as
    one pickle."""

    value: Any


def boxed(function: Callable[..., Any], *args: Any) -> Boxed:
    """Return ``function(*args)`` in a box (what a worker runs for every task)."""
    return Boxed(function(*args))


def _judge_on_cluster(
    task: Callable[[Any, Catalog, JudgeOptions], list[Result]],
    parts: list[Any],
    catalog: Catalog,
    options: JudgeOptions,
    address: str | None,
    workers: int | None,
    on_chunk: Callable[[list[Result]], None] | None,
) -> list[Result]:
    """Return ``task``'s results of every chunk, in the chunks' order, each chunk a task on the cluster."""
    client, cluster = connect(address, workers)
    try:
        shared = client.scatter(catalog, broadcast=True)
        futures = [client.submit(boxed, task, part, shared, options, pure=False) for part in parts]
        done = _in_order(futures, "Chunk", on_chunk)
        return [result for results in done for result in results]
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _in_order(futures: list[Any], what: str, on_each: Callable[[Any], None] | None) -> list[Any]:
    """Return the futures' (boxed) results in their order, calling ``on_each`` with each as it comes.

    The list is emptied: a future once read is let go, so its worker forgets the result.
    """
    from distributed import as_completed

    count = len(futures)
    index_of = {future.key: index for index, future in enumerate(futures)}
    pending = as_completed(futures)
    futures.clear()
    done: dict[int, Any] = {}
    for future in pending:
        index = index_of[future.key]
        try:
            done[index] = future.result().value
        except Exception as exc:  # Dask re-raises whatever the task raised, or KilledWorker
            raise ClusterError(f"{what} {index + 1} of {count} failed on the cluster: {exc!r}.") from exc
        if on_each is not None:
            on_each(done[index])
    return [done[index] for index in range(count)]


Item = TypeVar("Item")
Outcome = TypeVar("Outcome")


def map_on_cluster(
    function: Callable[[Item], Outcome],
    items: Sequence[Item],
    *,
    address: str | None = None,
    workers: int | None = None,
    on_result: Callable[[Outcome], None] | None = None,
) -> list[Outcome]:
    """Return ``function(item)`` for every item, in the items' order, each item one task on a Dask cluster.

    The cluster is the one at ``address``, or a new local one of ``workers`` processes (as
    ``connect`` makes). ``function`` should be a top-level function (or a ``functools.partial``
    of one), so that it travels to the workers by name; each item is usually a chunk of work
    worth far more than Dask's overhead of about a millisecond a task. ``on_result`` is called
    with each result as soon as its task is done (in the order the tasks finish), so a caller
    can show progress. A task that raises is a ``ClusterError`` naming which one; a worker that
    dies has its task run again elsewhere (Dask's ``allowed-failures``).
    """
    if not items:
        return []
    client, cluster = connect(address, workers)
    try:
        futures = [client.submit(boxed, function, item, pure=False) for item in items]
        return _in_order(futures, "Task", on_result)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
