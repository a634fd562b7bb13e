"""The --cluster / --workers / --chunk-size options of every command that can run on a Dask cluster.

One decorator adds the three options and turns them into one ``on_cluster`` argument (None: run
here), refusing --cluster and --workers together before any work starts. The builders below
turn that choice into what the lower layers take: a "judge these trials" callable for the
consensus and the crowd curve, a chunk mapper for the fit estimates. Dask is imported only when
a cluster is asked for.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import click

from causalplan.cli.common import exit_on_error, fail

if TYPE_CHECKING:
    from causalplan.consensus.judging import TrialJudge
    from causalplan.objects.catalog import Catalog
    from causalplan.sim.fit_estimates import ChunkMapper, ChunkOutcome, InsertionChunk
    from causalplan.transfer.batch import Trial, TrialResult

Command = Callable[..., None]


@dataclass(frozen=True)
class ClusterChoice:
    """Where to run: the scheduler at ``address``, or a new local cluster of ``workers`` processes."""

    address: str | None
    workers: int | None
    chunk_size: int


def _scheduler_address(context: click.Context, parameter: click.Parameter, address: str | None) -> str | None:
    """Return ``address`` when it names a host and port (Dask is loaded only when one is given)."""
    if address is None:
        return None
    from distributed.comm.addressing import get_address_host_port

    try:
        get_address_host_port(address)
    except ValueError as exc:
        raise click.BadParameter(f"{exc}; a scheduler's address looks like tcp://10.0.0.5:8786.") from exc
    return address


def cluster_options(unit: str = "trials", default_chunk_size: int = 250) -> Callable[[Command], Command]:
    """Return a decorator adding --cluster, --workers and --chunk-size (``unit`` go in a chunk).

    The command receives ``on_cluster``: a ``ClusterChoice``, or None when neither --cluster nor
    --workers is given (then --chunk-size on the command line is an error, not silently unused).
    """

    def decorate(command: Command) -> Command:
        @functools.wraps(command)
        def with_cluster(*args: Any, cluster: str | None, workers: int | None, chunk_size: int, **kwargs: Any) -> None:
            if cluster is not None and workers is not None:
                fail("invalid_option", "Give --cluster (an existing cluster) or --workers (a local one), not both.")
            given = click.get_current_context().get_parameter_source("chunk_size")
            if cluster is None and workers is None and given is click.core.ParameterSource.COMMANDLINE:
                fail("invalid_option", "--chunk-size sizes the tasks of a cluster: give --cluster or --workers too.")
            chosen = None if cluster is None and workers is None else ClusterChoice(cluster, workers, chunk_size)
            command(*args, on_cluster=chosen, **kwargs)

        options = (
            click.option(
                "--cluster",
                metavar="ADDRESS",
                callback=_scheduler_address,
                help="Run on the Dask cluster whose scheduler is at ADDRESS, e.g. tcp://10.0.0.5:8786, in chunks "
                "(the catalog travels with the work; the workers' Python needs causalplan installed).",
            ),
            click.option(
                "--workers",
                type=click.IntRange(1, 256),
                help=f"Run on a local Dask cluster of this many worker processes (one chunk of {unit} at a time "
                "each). Not with --cluster.",
            ),
            click.option(
                "--chunk-size",
                type=click.IntRange(1, 1_000_000),
                default=default_chunk_size,
                help=f"How many {unit} one cluster task holds (with --cluster or --workers).",
            ),
        )
        decorated: Command = with_cluster
        for option in reversed(options):
            decorated = option(decorated)
        return decorated

    return decorate


def trial_judge(
    on_cluster: ClusterChoice | None, catalog: Catalog, planner: str, time_limit: float, simulate: bool
) -> TrialJudge:
    """Return what judges trials: ``run_batch`` here, or ``run_batch_on_cluster`` on the chosen cluster."""
    from causalplan.consensus.judging import local_judge

    if on_cluster is None:
        return local_judge(catalog, planner, time_limit, simulate)
    choice = on_cluster

    def judge_on_cluster(trials: list[Trial], progress: Callable[[int], None] | None) -> list[TrialResult]:
        from causalplan.transfer.cluster import JudgeOptions, run_batch_on_cluster

        def chunk_done(results: list[TrialResult]) -> None:
            if progress is not None:
                progress(len(results))

        with exit_on_error():
            return run_batch_on_cluster(
                trials,
                catalog,
                JudgeOptions(planner, time_limit, simulate),
                address=choice.address,
                workers=choice.workers,
                chunk_size=choice.chunk_size,
                on_chunk=chunk_done,
            )

    return judge_on_cluster


def chunk_mapper(on_cluster: ClusterChoice | None) -> ChunkMapper | None:
    """Return what runs chunks of insertions on the chosen cluster (None: the fits are measured here)."""
    if on_cluster is None:
        return None
    choice = on_cluster

    def map_chunks(
        function: Callable[[InsertionChunk], ChunkOutcome],
        chunks: Sequence[InsertionChunk],
        on_result: Callable[[ChunkOutcome], None] | None,
    ) -> list[ChunkOutcome]:
        from causalplan.transfer.cluster import map_on_cluster

        with exit_on_error():
            return map_on_cluster(function, chunks, address=choice.address, workers=choice.workers, on_result=on_result)

    return map_chunks
