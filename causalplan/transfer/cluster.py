"""A batch of trials judged on a Dask distributed cluster: a scheduler's address, or a local one.

Trials go in chunks, not one task each: a trial takes a few milliseconds and Dask's own
overhead is near a millisecond a task, so one task per trial would spend most of the time on
scheduling. The catalog is sent to every worker once (``scatter(..., broadcast=True)``), each
chunk is ``run_batch`` on a worker (so its caches work within the chunk and across the chunks
that worker gets), and the chunks' results come back as they finish. A worker that dies in
the middle of a chunk has that chunk run again elsewhere, which Dask does on its own (its
``allowed-failures`` setting); the chunk's future then holds exactly one result, so nothing is
lost or counted twice. The verdicts are those of the local batch, in the trials' order.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeVar

from causalplan.errors import CausalPlanError
from causalplan.objects.catalog import Catalog
from causalplan.transfer.batch import Judge, Trial, TrialResult, run_batch

if TYPE_CHECKING:
    from distributed import Client

DEFAULT_CHUNK_SIZE = 250
CONNECT_TIMEOUT = "10s"


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
    """The last judge of each verdict (e.g. ``sim.robot_verdict.robot_judged``): a top-level function,
    so it travels to the workers by name."""


def judge_chunk(trials: list[Trial], catalog: Catalog, options: JudgeOptions) -> list[TrialResult]:
    """Return the results of one chunk of trials (the task a worker runs)."""
    return run_batch(
        trials, catalog, options.planner, options.time_limit, options.simulate, val=options.val, judge=options.judge
    )


def chunks(trials: Sequence[Trial], size: int) -> list[list[Trial]]:
    """Return the trials cut into consecutive chunks of ``size`` (the last may be shorter)."""
    return [list(trials[start : start + size]) for start in range(0, len(trials), size)]


def connect(address: str | None, workers: int | None) -> tuple[Client, Any]:
    """Return a client of the cluster at ``address``, or of a new local cluster of ``workers`` processes.

    The second value is the local cluster to close after the client (None for a remote one).
    """
    from distributed import Client, LocalCluster

    if address is not None:
        try:
            return Client(address, timeout=CONNECT_TIMEOUT), None
        except (OSError, TimeoutError) as exc:
            raise ClusterError(
                f"Cannot reach the Dask scheduler at {address}: {exc}. Is `dask scheduler` running there?",
                details={"address": address},
            ) from exc
    cluster = LocalCluster(
        n_workers=workers or 1,
        threads_per_worker=1,  # the planners keep per-process state; one trial at a time per process
        processes=True,
        dashboard_address=None,
        silence_logs=logging.ERROR,
    )
    return Client(cluster), cluster


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
    from distributed import as_completed

    if chunk_size < 1:
        raise ClusterError(f"The chunk size must be at least 1; got {chunk_size}.")
    parts = chunks(trials, chunk_size)
    client, cluster = connect(address, workers)
    try:
        shared = client.scatter(catalog, broadcast=True)
        futures = {
            client.submit(judge_chunk, part, shared, options, pure=False): index for index, part in enumerate(parts)
        }
        done: dict[int, list[TrialResult]] = {}
        for future in as_completed(futures):
            index = futures[future]
            try:
                results = future.result()
            except Exception as exc:  # Dask re-raises whatever the chunk raised, or KilledWorker
                raise ClusterError(f"Chunk {index + 1} of {len(parts)} failed on the cluster: {exc!r}.") from exc
            done[index] = results
            if on_chunk is not None:
                on_chunk(results)
        return [result for index in range(len(parts)) for result in done[index]]
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


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
    from distributed import as_completed

    if not items:
        return []
    client, cluster = connect(address, workers)
    try:
        futures = {client.submit(function, item, pure=False): index for index, item in enumerate(items)}
        done: dict[int, Outcome] = {}
        for future in as_completed(futures):
            index = futures[future]
            try:
                done[index] = future.result()
            except Exception as exc:  # Dask re-raises whatever the task raised, or KilledWorker
                raise ClusterError(f"Task {index + 1} of {len(items)} failed on the cluster: {exc!r}.") from exc
            if on_result is not None:
                on_result(done[index])
        return [done[index] for index in range(len(items))]
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
