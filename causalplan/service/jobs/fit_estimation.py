"""The ``fit_estimation`` kind of job: ``causalplan estimate-fits`` over HTTP.

Progress counts trials (insertions). In the service's own pool each fit is one call of a
planner worker (the robot's nominal run, then the noisy trials), so progress moves a fit at a
time and a cancel stops the job before the next fit. With a Dask scheduler named, the fits'
insertions go to the cluster in chunks (``estimate_fits`` with a chunk mapper, as the CLI's
``--cluster``), progress moves a chunk at a time, and a cancel closes the cluster's client.
Either way the numbers are the CLI's for the same seed: every fit draws its noise from its own
seeded generator, so fits estimated one by one, or in chunks, give what one run gives.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from causalplan.limits import LimitExceededError
from causalplan.service.errors import InvalidRequestError
from causalplan.service.jobs.requests import FitEstimationRequest
from causalplan.service.jobs.work import Progress, in_pool
from causalplan.service.work.batches import FitEstimateArguments
from causalplan.service.work.registry import FIT_ESTIMATE

if TYPE_CHECKING:
    from causalplan.service.api.schemas.jobs import FitEstimationJobIn
    from causalplan.service.deps import Services
    from causalplan.sim.fit_estimates import ChunkOutcome, InsertionChunk


def prepare_fit_estimation(body: FitEstimationJobIn, services: Services) -> FitEstimationRequest:
    obj = services.catalog.get(body.object)  # unknown_object (404), with a suggestion
    known = [fit.id for fit in obj.fits]
    asked = list(body.fits)
    unknown = [fit for fit in asked if fit not in known]
    if unknown:
        raise InvalidRequestError(
            f"The {obj.name} has no fit '{unknown[0]}'; its fits are: {', '.join(sorted(known))}.",
            details={"fit": unknown[0], "fits": sorted(known)},
        )
    chosen = [fit for fit in known if not asked or fit in asked]
    if not chosen:
        raise InvalidRequestError(f"The {obj.name} has no fits to estimate.", details={"object": obj.id})
    trials = body.trials
    limit, count = services.settings.max_job_trials, trials * len(chosen)
    if count > limit:
        raise LimitExceededError(
            "too_many_trials",
            f"{len(chosen)} fit(s) of {trials} trials each are {count} trials; "
            f"this server takes at most {limit} per job.",
            details={"limit": limit, "actual": count},
        )
    return FitEstimationRequest(
        object=obj.id,
        fits=chosen,
        count=count,
        trials=trials,
        seed=body.seed,
        noise_mm=body.noise_mm,
        noise_deg=body.noise_deg,
    )


def _on_cluster(request: FitEstimationRequest, services: Services, progress: Progress) -> list[dict[str, object]]:
    """Return the fits' estimates, their insertions run in chunks on the Dask cluster the settings name."""
    from causalplan.sim.fit_estimates import estimate_fits
    from causalplan.transfer.cluster import map_on_cluster

    address = services.settings.dask_scheduler
    fit_ids, trials = request.fits, request.trials
    total, done = trials * len(fit_ids), 0

    def map_chunks(
        function: Callable[[InsertionChunk], ChunkOutcome],
        chunks: Sequence[InsertionChunk],
        on_result: Callable[[ChunkOutcome], None] | None,
    ) -> list[ChunkOutcome]:
        return map_on_cluster(function, chunks, address=address, on_result=on_result)

    def on_insertions(count: int) -> None:
        nonlocal done
        done += count
        progress(done, total)  # raises JobCancelledError on a cancel: the cluster's client is closed

    obj = services.catalog.get(request.object)
    seed, noise_mm, noise_deg = request.seed, request.noise_mm, request.noise_deg
    estimates = estimate_fits(
        obj, trials, seed, noise_mm, noise_deg, fit_ids, map_chunks=map_chunks, progress=on_insertions
    )
    return [estimate.as_dict() for estimate in estimates]


def _in_pool(request: FitEstimationRequest, services: Services, progress: Progress) -> list[dict[str, object]]:
    """Return the fits' estimates, each fit one call of a planner worker."""
    fit_ids, trials = request.fits, request.trials
    rows: list[dict[str, object]] = []
    for fit_id in fit_ids:
        arguments = FitEstimateArguments(
            request.object, fit_id, trials, request.seed, request.noise_mm, request.noise_deg
        )
        rows.append(in_pool(services, progress, FIT_ESTIMATE, arguments))
        progress(len(rows) * trials, len(fit_ids) * trials)
    return rows


def run_fit_estimation_job(request: FitEstimationRequest, services: Services, progress: Progress) -> dict[str, Any]:
    """Estimate the fits; return what ``causalplan estimate-fits --json`` prints, and the overlay."""
    from causalplan.objects.overlay import overlay_data

    object_id, trials = request.object, request.trials
    seed, noise_mm, noise_deg = request.seed, request.noise_mm, request.noise_deg
    progress(0, trials * len(request.fits))
    on_cluster = services.settings.dask_scheduler is not None
    rows = (_on_cluster if on_cluster else _in_pool)(request, services, progress)
    command = (
        f"causalplan estimate-fits {object_id} --trials {trials} --seed {seed} "
        f"--noise-mm {noise_mm:g} --noise-deg {noise_deg:g}"
    )
    return {
        "object": object_id,
        "noise": {"mm": noise_mm, "deg": noise_deg},
        "seed": seed,
        "fits": rows,
        "overlay": overlay_data({object_id: rows}, command),
    }
