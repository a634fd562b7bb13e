"""The ``fit_estimation`` kind of job: ``causalplan estimate-fits`` over HTTP, one fit at a time.

Each fit is one call of a planner worker (the robot's nominal run, then the noisy trials), so
the job's progress counts fits and a cancel stops it before the next fit. The numbers are the
CLI's for the same seed: every fit draws its noise from its own seeded generator, so
estimating fits one by one gives what estimating them together gives.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from causalplan.service.errors import InvalidRequestError, LimitExceededError
from causalplan.service.jobs.work import Progress, in_pool

if TYPE_CHECKING:
    from causalplan.service.deps import Services

TRIAL_SECONDS = 0.1
"""A generous bound on one noisy insertion, for a fit's time limit in a worker (a trial is far quicker)."""


def estimate_fit_job(
    object_id: str,
    fit_id: str,
    trials: int,
    seed: int,
    noise_mm: float,
    noise_deg: float,
    catalog_folders: tuple[Path, ...],
) -> dict[str, object]:
    """Return ``FitEstimate.as_dict()`` of one fit of the object (runs in a planner worker)."""
    from causalplan.service.pool.jobs import worker_catalog
    from causalplan.sim.fit_estimates import estimate_fits

    obj = worker_catalog(catalog_folders).get(object_id)
    (estimate,) = estimate_fits(obj, trials, seed, noise_mm, noise_deg, (fit_id,))
    return estimate.as_dict()


def prepare_fit_estimation(request: dict[str, Any], services: Services) -> dict[str, Any]:
    obj = services.catalog.get(str(request["object"]))  # unknown_object (404), with a suggestion
    known = [fit.id for fit in obj.fits]
    asked: list[str] = list(request.get("fits") or [])
    unknown = [fit for fit in asked if fit not in known]
    if unknown:
        raise InvalidRequestError(
            f"The {obj.name} has no fit '{unknown[0]}'; its fits are: {', '.join(sorted(known))}.",
            details={"fit": unknown[0], "fits": sorted(known)},
        )
    chosen = [fit for fit in known if not asked or fit in asked]
    if not chosen:
        raise InvalidRequestError(f"The {obj.name} has no fits to estimate.", details={"object": obj.id})
    trials = int(request["trials"])
    limit = services.settings.max_job_trials
    if trials * len(chosen) > limit:
        raise LimitExceededError(
            "too_many_trials",
            f"{len(chosen)} fit(s) of {trials} trials each are {trials * len(chosen)} trials; "
            f"this server takes at most {limit} per job.",
            details={"limit": limit, "actual": trials * len(chosen)},
        )
    return {
        "object": obj.id,
        "fits": chosen,
        "count": len(chosen),
        "trials": trials,
        "seed": int(request["seed"]),
        "noise_mm": float(request["noise_mm"]),
        "noise_deg": float(request["noise_deg"]),
    }


def run_fit_estimation_job(request: dict[str, Any], services: Services, progress: Progress) -> dict[str, Any]:
    """Estimate the fits one by one; return what ``causalplan estimate-fits --json`` prints, and the overlay."""
    from causalplan.objects.overlay import overlay_data

    settings = services.settings
    object_id, fit_ids, trials = str(request["object"]), list(request["fits"]), int(request["trials"])
    seed, noise_mm, noise_deg = int(request["seed"]), float(request["noise_mm"]), float(request["noise_deg"])
    folders = tuple(settings.catalog_folders)
    timeout = settings.robot_seconds + trials * TRIAL_SECONDS
    rows: list[dict[str, object]] = []
    progress(0, len(fit_ids))
    for fit_id in fit_ids:
        args = (object_id, fit_id, trials, seed, noise_mm, noise_deg, folders)
        rows.append(in_pool(services, estimate_fit_job, args, timeout))
        progress(len(rows), len(fit_ids))
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
