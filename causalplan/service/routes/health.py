"""GET /health: planner binaries and versions, registries, database, pool, cache and limits."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter
from sqlalchemy import text
from sqlalchemy.exc import SQLAlchemyError

import causalplan
from causalplan.service.db.migrate import current_revision
from causalplan.service.deps import Services, ServicesDep
from causalplan.service.schemas import DatabaseHealthOut, FastDownwardHealthOut, HealthOut
from causalplan.service.submissions import default_planner

router = APIRouter(tags=["health"])

PROBE_WAIT_SECONDS = 30.0


def database_health(services: Services) -> DatabaseHealthOut:
    """Return whether the database answers, and its schema revision."""
    backend = services.engine.dialect.name
    expected = services.revision  # what start-up migrated to: the newest the package ships
    try:
        with services.engine.connect() as connection:
            connection.execute(text("SELECT 1"))
        revision = current_revision(services.engine)
    except SQLAlchemyError as exc:
        reason = str(getattr(exc, "orig", None) or exc).strip().splitlines()[0]
        return DatabaseHealthOut(
            reachable=False, backend=backend, revision=None, expected_revision=expected, problem=reason
        )
    problem = None if revision == expected else f"schema revision {revision}, expected {expected}"
    return DatabaseHealthOut(
        reachable=True, backend=backend, revision=revision, expected_revision=expected, problem=problem
    )


@router.get("/health", response_model=HealthOut, summary="Is the service able to plan and store?")
def health(services: ServicesDep) -> HealthOut:
    """Report the planner registry, Fast Downward's binary and versions, optional backends that
    failed to import, the database, the worker pool, the cache and the request limits.

    `status` is 'ok' when Fast Downward is found and the database is reachable at the right
    schema, else 'degraded' (the answer is still 200: the service is up).
    """
    services.probe_done.wait(PROBE_WAIT_SECONDS)
    probe: dict[str, Any] = services.probe or {}
    fast_downward = probe.get("fast_downward")
    database = database_health(services)
    planner_ok = bool(fast_downward and fast_downward["search_binary_found"] and fast_downward["translator_found"])
    settings = services.settings
    return HealthOut(
        status="ok" if planner_ok and database.reachable and database.problem is None else "degraded",
        version=causalplan.__version__,
        planners=probe.get("planners"),
        default_planner=default_planner(),
        fast_downward=FastDownwardHealthOut.model_validate(fast_downward) if fast_downward else None,
        optional_backends_failed=probe.get("optional_backends_failed"),
        database=database,
        pool=services.pool.stats().as_dict(),
        cache=services.cache.stats(),
        repeats=services.repeats.stats(),
        limits={
            "max_body_bytes": settings.max_body_bytes,
            "max_label_length": settings.max_label_length,
            "max_parts": settings.max_parts,
            "max_labels_per_part": settings.max_labels_per_part,
            "max_rules": settings.max_rules,
            "default_time_limit": settings.default_time_limit,
            "max_time_limit": settings.max_time_limit,
        },
    )
