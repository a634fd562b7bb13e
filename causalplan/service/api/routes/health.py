"""GET /health (liveness: the planners, the database, free space, the pools, the jobs, the cache,
the limits) and GET /health/ready (readiness: the planner pool has answered a plan)."""

from __future__ import annotations

import logging
import os
import shutil
from pathlib import Path
from typing import Any

from fastapi import APIRouter
from sqlalchemy.exc import SQLAlchemyError

from causalplan.errors import CausalPlanError
from causalplan.service.api.schemas.common import error_responses
from causalplan.service.api.schemas.health import (
    DatabaseHealthOut,
    FastDownwardHealthOut,
    HealthOut,
    JobsHealthOut,
    ReadyOut,
    StorageHealthOut,
)
from causalplan.service.deps import Services, ServicesDep
from causalplan.service.documents import default_planner
from causalplan.service.errors import NotReadyError
from causalplan.service.jobs.kinds import KINDS
from causalplan.service.readiness import STARTING
from causalplan.service.storage import jobs as job_store
from causalplan.service.storage.health import is_server_read_only, ping
from causalplan.service.storage.migrate import current_revision
from causalplan.service.storage.session import sqlite_path
from causalplan.version import __version__

logger = logging.getLogger(__name__)

router = APIRouter(tags=["health"])

PROBE_WAIT_SECONDS = 30.0
MEGABYTE = 1024 * 1024


def _write_problem(engine_backend: str, services: Services) -> str | None:
    """Return why the database cannot be written (None when it can, as far as can be told without writing)."""
    path = sqlite_path(services.settings.database_url)
    if path is not None:
        for place in (path, path.parent):
            if place.exists() and not os.access(place, os.W_OK):
                return f"the SQLite {'file' if place == path else 'folder'} is read-only"
        return None
    if engine_backend == "postgresql" and is_server_read_only(services.engine):
        return "the database server is read-only"
    return None


def database_health(services: Services) -> DatabaseHealthOut:
    """Return whether the database answers and takes writes, and its schema revision."""
    backend = services.engine.dialect.name
    expected = services.revision  # what start-up migrated to: the newest the package ships
    try:
        ping(services.engine)
        revision = current_revision(services.engine)
        read_only = _write_problem(backend, services)
    except SQLAlchemyError as exc:
        logger.warning("/health: the database did not answer: %s", exc)  # the driver's words stay in the log
        return DatabaseHealthOut(
            reachable=False,
            backend=backend,
            revision=None,
            expected_revision=expected,
            problem="the database did not answer; the server log says why",
        )
    problem = read_only or (None if revision == expected else f"schema revision {revision}, expected {expected}")
    return DatabaseHealthOut(
        reachable=True, backend=backend, revision=revision, expected_revision=expected, problem=problem
    )


def storage_health(services: Services) -> StorageHealthOut:
    """Return the free space where data is stored (the SQLite file's folder, else the data folder)."""
    settings = services.settings
    path = sqlite_path(settings.database_url)
    folder: Path = path.parent if path is not None else settings.data_folder
    while not folder.exists() and folder != folder.parent:  # not made yet: the disk it will be on
        folder = folder.parent
    try:
        free_mb = shutil.disk_usage(folder).free // MEGABYTE
    except OSError:
        return StorageHealthOut(free_mb=None, min_free_mb=settings.min_free_disk_mb, problem="free space unknown")
    problem = None
    if free_mb < settings.min_free_disk_mb:
        problem = f"only {free_mb} MB free where data is stored (at least {settings.min_free_disk_mb} MB wanted)"
    return StorageHealthOut(free_mb=free_mb, min_free_mb=settings.min_free_disk_mb, problem=problem)


def jobs_health(services: Services) -> JobsHealthOut:
    """Return the jobs queued and running across replicas, and this replica's runners."""
    runner = services.runner.stats() if services.runner is not None else {"threads": 0, "busy": 0}
    counts: dict[str, int | None] = {"queued": None, "running": None}
    problem = None
    try:
        counts.update(job_store.count_unfinished(services.engine))
    except (CausalPlanError, SQLAlchemyError):
        problem = "the jobs could not be counted: the database did not answer"
    return JobsHealthOut(
        queued=counts["queued"],
        running=counts["running"],
        runners=runner["threads"],
        runners_busy=runner["busy"],
        kinds=[kind.value for kind in KINDS],
        cluster=services.settings.dask_scheduler is not None,
        problem=problem,
    )


@router.get("/health", response_model=HealthOut, summary="Is the service able to plan and store?")
def read_health(services: ServicesDep) -> HealthOut:
    """Report the planner registry, Fast Downward, optional backends that failed to import, the
    database, free space, the worker pools (interactive requests', jobs'), the jobs (queued and
    running across replicas, this replica's runners), the cache and the request limits.

    `status` is 'ok' when Fast Downward can run, the database answers and takes writes at the
    right schema, and there is enough free space; else 'degraded' (the answer is still 200:
    the service is up).
    """
    services.probe_done.wait(PROBE_WAIT_SECONDS)
    probe: dict[str, Any] = services.probe or {}
    fast_downward = probe.get("fast_downward")
    database = database_health(services)
    storage = storage_health(services)
    planner_ok = bool(fast_downward and fast_downward["available"])
    is_ok = planner_ok and database.reachable and database.problem is None and storage.problem is None
    settings = services.settings
    return HealthOut(
        status="ok" if is_ok else "degraded",
        version=__version__,
        planners=probe.get("planners"),
        default_planner=default_planner(),
        fast_downward=FastDownwardHealthOut.model_validate(fast_downward) if fast_downward else None,
        optional_backends_failed=probe.get("optional_backends_failed"),
        database=database,
        storage=storage,
        pool=services.pool.stats().as_dict(),
        job_pool=services.job_pool.stats().as_dict(),
        jobs=jobs_health(services),
        cache=services.caches.answers.stats(),
        limits={
            "max_body_bytes": settings.max_body_bytes,
            "max_label_length": settings.max_label_length,
            "max_parts": settings.max_parts,
            "max_labels_per_part": settings.max_labels_per_part,
            "max_rules": settings.max_rules,
            "default_time_limit": settings.default_time_limit,
            "max_time_limit": settings.max_time_limit,
            "robot_seconds": settings.robot_seconds,
            "max_job_trials": settings.max_job_trials,
            "max_queued_jobs": settings.max_queued_jobs,
            "jobs_in_flight": settings.jobs_in_flight,
            "job_megabytes": settings.job_megabytes,
            "jobs_per_minute": settings.jobs_per_minute,
            "anonymous_jobs_in_flight": settings.anonymous_jobs_in_flight,
            "anonymous_job_megabytes": settings.anonymous_job_megabytes,
            "anonymous_jobs_per_minute": settings.anonymous_jobs_per_minute,
        },
    )


@router.get(
    "/health/ready",
    response_model=ReadyOut,
    summary="Does this replica take participants now?",
    responses=error_responses(503),
)
def read_readiness(services: ServicesDep) -> ReadyOut:
    """Answer 200 once this replica's planner pool has answered a plan of its own; before, 503
    (`not_ready`, with `Retry-After`).

    `/health` answers as soon as the app is up (liveness: restart the replica when it fails);
    this is what a load balancer or a deploy waits for before sending participants, so nobody
    waits for the workers to warm.
    """
    readiness = services.readiness
    if not readiness.is_ready():
        raise NotReadyError(f"Not ready yet: {readiness.problem or STARTING}.")
    return ReadyOut(status="ready")
