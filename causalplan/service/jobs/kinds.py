"""What each kind of job does: read its upload when it is posted, then do the work when a runner takes it.

A kind is a ``JobKind`` with ``prepare`` (at POST time, on the request's thread: refuse what
is wrong with a clear error before anything is queued, and return the request to store, a
model of ``jobs.requests``), ``read`` (that model from the job's row) and ``run`` (in a runner
thread of whichever replica took the job). Adding a
kind is one enum member and one entry in ``KINDS``; the longer kinds live in modules of their
own (``video``, ``fit_estimation``, ``troubleshooting``).
"""

from __future__ import annotations

import io
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from causalplan.errors import InputFileError
from causalplan.limits import LimitExceededError
from causalplan.service.errors import InvalidRequestError, WorkerDiedError
from causalplan.service.jobs.fit_estimation import prepare_fit_estimation, run_fit_estimation_job
from causalplan.service.jobs.requests import (
    BatchRequest,
    ConsensusRequest,
    FitEstimationRequest,
    SimulationRequest,
    TroubleshootingRequest,
    read_video_request,
)
from causalplan.service.jobs.troubleshooting import prepare_troubleshooting, run_troubleshooting_job
from causalplan.service.jobs.video import prepare_video, run_video_job
from causalplan.service.jobs.work import Kind, Progress, in_pool, in_pool_retried
from causalplan.service.storage.jobs import JobKind
from causalplan.service.work.batches import ConsensusArguments, TrialsArguments
from causalplan.service.work.planning import SimulationArguments
from causalplan.service.work.registry import CONSENSUS, JUDGED_TRIALS, QUEUED_SIMULATION, Work
from causalplan.transfer import batch
from causalplan.transfer.batch import Trial, TrialResult, repeated_ids, trials_of_lines, undecided_results

if TYPE_CHECKING:
    from causalplan.service.api.schemas.jobs import BatchJobIn, ConsensusJobIn, SimulationJobIn
    from causalplan.service.deps import Services

CHUNK_SIZE = 20
"""Trials a planner worker judges per call: small enough for steady progress and a prompt cancel."""
MAX_REPEATED_IDS_NAMED = 100
"""A batch result names at most this many ids that several trials share."""


# -- batch --------------------------------------------------------------------------------------


def csv_to_json_lines(text: str) -> str:
    """Return a CSV upload as JSON Lines (``transfer.batch.csv_to_json_lines``); its problems are 422s."""
    try:
        return batch.csv_to_json_lines(text)
    except InputFileError as exc:
        raise InvalidRequestError(exc.message, details=exc.details) from None


def read_uploaded_trials(text: str, limit: int) -> list[Trial]:
    """Return the trials of a JSON Lines upload, read as ``causalplan batch`` reads a file; at most ``limit``."""
    lines = io.BytesIO(text.encode("utf-8", errors="surrogatepass"))  # split as a file is: at each b"\n"
    trials = list(trials_of_lines(enumerate(lines, start=1)))
    if len(trials) > limit:
        raise LimitExceededError(
            "too_many_trials",
            f"The upload has {len(trials)} trials; this server takes at most {limit} per job.",
            details={"limit": limit, "actual": len(trials)},
        )
    if not trials:
        raise InvalidRequestError("The upload has no trials: one JSON object a line, with 'model' and 'mapping'.")
    return trials


def prepare_batch(body: BatchJobIn, services: Services) -> BatchRequest:
    from causalplan.service.documents import resolve_planner, resolve_time_limit

    lines = csv_to_json_lines(body.trials) if body.format == "csv" else body.trials
    trials = read_uploaded_trials(lines, services.settings.max_job_trials)
    return BatchRequest(
        trials=lines,
        count=len(trials),
        planner=resolve_planner(body.planner),
        time_limit=resolve_time_limit(body.time_limit, services.settings),
        simulate=body.simulate,
        validate=body.validate_plan,
    )


def _summary(results: list[TrialResult]) -> dict[str, Any]:
    counts: dict[str, int] = {}
    for result in results:
        counts[result.verdict.verdict.value] = counts.get(result.verdict.verdict.value, 0) + 1
    repeated = repeated_ids(result.trial_id for result in results)
    return {
        "trials": len(results),
        "verdicts": counts,
        "repeated_ids": dict(list(repeated.items())[:MAX_REPEATED_IDS_NAMED]),
        "results": [result.row() for result in results],
    }


def run_batch_job(request: BatchRequest, services: Services, progress: Progress) -> dict[str, Any]:
    settings = services.settings
    trials = read_uploaded_trials(request.trials, settings.max_job_trials)
    planner, time_limit, simulate = request.planner, request.time_limit, request.simulate
    val = request.validate_plan
    total = len(trials)
    progress(0, total)
    if settings.dask_scheduler is not None:
        from causalplan.transfer.cluster import JudgeOptions, run_batch_on_cluster

        done = 0

        def on_chunk(results: list[TrialResult]) -> None:
            nonlocal done
            done += len(results)
            progress(done, total)  # raises JobCancelledError on a cancel: the cluster's client is closed

        ordered = run_batch_on_cluster(
            trials,
            services.catalog,
            JudgeOptions(planner, time_limit, simulate, val),
            address=settings.dask_scheduler,
            on_chunk=on_chunk,
        )
        return _summary(ordered)

    def chunk_arguments(chunk: tuple[Trial, ...]) -> TrialsArguments:
        return TrialsArguments(chunk, planner, time_limit, simulate, val)

    return _summary(judge_in_chunks(services, progress, trials, chunk_arguments))


def judge_in_chunks(
    services: Services,
    progress: Progress,
    trials: list[Trial],
    arguments: Callable[[tuple[Trial, ...]], TrialsArguments],
    work: Work[TrialsArguments, list[TrialResult]] = JUDGED_TRIALS,
) -> list[TrialResult]:
    """Return ``work`` done on every chunk of ``trials`` (its ``arguments``), in the jobs' workers, in order.

    A dead worker costs one chunk, not the job: the trials judged are kept, the chunk that was
    running is run once more on a fresh worker, and if that worker dies too its trials are
    ``undecided`` (reason ``worker_crashed``) and the batch goes on.
    """
    results: list[TrialResult] = []
    for start in range(0, len(trials), CHUNK_SIZE):
        chunk = tuple(trials[start : start + CHUNK_SIZE])
        try:
            judged = in_pool_retried(services, progress, work, arguments(chunk))
        except WorkerDiedError as exc:
            message = (
                f"The worker judging trials {start + 1}-{start + len(chunk)} died twice "
                f"(exit code {exc.details['exit_code']}); they were not judged."
            )
            judged = undecided_results(list(chunk), "worker_crashed", message)
        results.extend(judged)
        progress(len(results), len(trials))
    return results


# -- simulation ---------------------------------------------------------------------------------


def prepare_simulation(body: SimulationJobIn, services: Services) -> SimulationRequest:
    from causalplan.service.documents import plan_inputs
    from causalplan.service.storage.crud import ClientIds

    if body.video is not None:
        raise InvalidRequestError(
            'A simulation job makes no film: post the same request with "kind": "video" (the film is '
            "then served from the job, by any replica).",
            details={"field": "video"},
        )
    inputs = plan_inputs(body, services, ClientIds())
    inputs.store(services)
    return SimulationRequest(
        model_id=str(inputs.submission.record.id),
        mapping=body.mapping,
        planner=inputs.planner,
        time_limit=inputs.time_limit,
        picture=body.picture,
        robot=body.robot,
        validate=body.validate_plan,
        motors=body.motors,
    )


def run_simulation_job(request: SimulationRequest, services: Services, progress: Progress) -> dict[str, Any]:
    from causalplan.service.api.schemas.plans import SimulationIn
    from causalplan.service.documents import plan_inputs
    from causalplan.service.storage.crud import ClientIds

    body = SimulationIn.model_validate(request.stored())
    inputs = plan_inputs(body, services, ClientIds())
    progress(0, 1)
    arguments = SimulationArguments(
        inputs.model,
        inputs.mapping,
        inputs.planner,
        inputs.time_limit,
        body.picture,
        body.robot,
        body.validate_plan,
        body.motors,
    )
    data = in_pool(services, progress, QUEUED_SIMULATION, arguments)
    progress(1, 1)
    return {**data, "model_id": request.model_id}


# -- consensus ----------------------------------------------------------------------------------


def prepare_consensus(body: ConsensusJobIn, services: Services) -> ConsensusRequest:
    from causalplan.service.documents import resolve_planner, resolve_time_limit

    count = len([line for line in body.trials.splitlines() if line.strip()])
    if count == 0:
        raise InvalidRequestError("The upload has no participants: one JSON object a line, with 'id' and 'model'.")
    if count > services.settings.max_job_trials:
        raise LimitExceededError(
            "too_many_trials",
            f"The upload has {count} lines; this server takes at most {services.settings.max_job_trials} per job.",
            details={"limit": services.settings.max_job_trials, "actual": count},
        )
    return ConsensusRequest(
        trials=body.trials,
        count=count,
        min_support=body.min_support,
        planner=resolve_planner(body.planner),
        time_limit=resolve_time_limit(body.time_limit, services.settings),
        simulate=body.simulate,
    )


def run_consensus_job(request: ConsensusRequest, services: Services, progress: Progress) -> dict[str, Any]:
    progress(0, 1)
    arguments = ConsensusArguments(
        request.trials, request.count, request.min_support, request.planner, request.time_limit, request.simulate
    )
    data = in_pool(services, progress, CONSENSUS, arguments)
    progress(1, 1)
    return data


KINDS: dict[JobKind, Kind[Any, Any]] = {
    JobKind.BATCH: Kind(prepare_batch, BatchRequest.model_validate, run_batch_job),
    JobKind.SIMULATION: Kind(prepare_simulation, SimulationRequest.model_validate, run_simulation_job),
    JobKind.CONSENSUS: Kind(prepare_consensus, ConsensusRequest.model_validate, run_consensus_job),
    JobKind.VIDEO: Kind(prepare_video, read_video_request, run_video_job),
    JobKind.FIT_ESTIMATION: Kind(prepare_fit_estimation, FitEstimationRequest.model_validate, run_fit_estimation_job),
    JobKind.TROUBLESHOOTING: Kind(
        prepare_troubleshooting, TroubleshootingRequest.model_validate, run_troubleshooting_job
    ),
}
