"""The answer of /health."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from causalplan.service.api.schemas.common import OutputModel


class DatabaseHealthOut(OutputModel):
    reachable: bool
    backend: str
    revision: str | None
    expected_revision: str
    problem: str | None = None


class FastDownwardHealthOut(OutputModel):
    available: bool = Field(description="Whether its planner can run here (its search binary and translator found).")
    versions: dict[str, str | None]
    problem: str | None = None


class StorageHealthOut(OutputModel):
    free_mb: int | None = Field(description="Free space where the data is stored (null: not known).")
    min_free_mb: int
    problem: str | None = None


class JobsHealthOut(OutputModel):
    queued: int | None = Field(description="Jobs waiting for a runner, across all replicas (null: database down).")
    running: int | None = Field(description="Jobs some replica's runner is doing now (null: database down).")
    runners: int = Field(description="This replica's runner threads (the setting job_runners; 0: it only answers).")
    runners_busy: int = Field(description="This replica's runner threads doing a job now.")
    kinds: list[str] = Field(description="The kinds of job this replica can do.")
    cluster: bool = Field(
        description="Whether batch and fit_estimation jobs run on a Dask cluster (else in this replica's pool)."
    )
    problem: str | None = None


class PlannerHealthOut(OutputModel):
    name: str
    available: bool
    problem: str | None = Field(description="Why it cannot run here (null when it can).")


class HealthOut(OutputModel):
    """Whether the service can plan and store, and what it runs with."""

    status: Literal["ok", "degraded"]
    version: str
    planners: list[PlannerHealthOut] | None = Field(
        description="The planner registry as a worker sees it (null until the first probe has finished)."
    )
    default_planner: str = Field(description="What 'auto' (the default) runs as on this server.")
    fast_downward: FastDownwardHealthOut | None
    optional_backends_failed: dict[str, str] | None = Field(
        description="Optional modules that failed to import in a planner worker, with why (null: not probed yet)."
    )
    database: DatabaseHealthOut
    storage: StorageHealthOut
    pool: dict[str, int] = Field(description="The interactive requests' workers (plans, transfers, checks).")
    job_pool: dict[str, int] = Field(
        description="The jobs' workers, one per runner thread (started with the first job); never the pool's."
    )
    jobs: JobsHealthOut
    cache: dict[str, int]
    limits: dict[str, int | float]


class ReadyOut(OutputModel):
    """This replica takes participants now (``GET /health/ready``; 503 in the error shape before)."""

    status: Literal["ready"]
