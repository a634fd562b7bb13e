"""Ready means ready: ``/health/ready`` says 503 until the planner pool has answered a plan of its own."""

from __future__ import annotations

from pathlib import Path

from causalplan.objects.catalog import load_catalog
from causalplan.service.pool.pool import PlannerPool
from causalplan.service.readiness import STARTING, Readiness, prove_ready, readiness_model
from causalplan.service.work.calls import ResultCache, Workers
from tests.service.fixtures import error_of, running_client, services_of, settings_for, sqlite_url


def test_the_readiness_model_needs_every_part_of_the_desk_lamp() -> None:
    settings = settings_for("sqlite://")
    model = readiness_model(load_catalog(settings.catalog_folders))
    assert model.labelling.object_id == "desk_lamp"
    (rule,) = model.rules
    assert len(rule.causes) == len(model.labelling.functions) == 3


def test_ready_is_503_until_the_pool_has_answered_then_200(tmp_path: Path) -> None:
    with running_client(settings_for(sqlite_url(tmp_path), planning_workers=1)) as client:
        services = services_of(client)
        proven = services.readiness
        services.readiness = Readiness()  # as a replica is before its first plan
        try:
            waiting = client.get("/health/ready")
            assert error_of(waiting, 503)["code"] == "not_ready"
            assert STARTING in waiting.json()["error"]["message"]
            assert waiting.headers["Retry-After"] == "1"
            assert client.get("/health").status_code == 200  # liveness answers meanwhile
        finally:
            services.readiness = proven
        assert proven.ready.wait(120.0)  # the signal the start-up plan gives
        assert services.pool.stats().completed >= 1  # a worker answered it, not the cache
        assert client.get("/health/ready").json() == {"status": "ready"}


def test_a_pool_that_cannot_plan_never_says_ready() -> None:
    settings = settings_for("sqlite://")
    closed = PlannerPool(1, 0, settings.worker_memory_mb, queue_wait_seconds=1.0)
    closed.close()
    readiness = Readiness()
    work = Workers(closed, closed, settings, ResultCache(1), "catalog")
    prove_ready(work, load_catalog(settings.catalog_folders), "fd", readiness)
    assert not readiness.is_ready()
    assert readiness.problem is not None and "planner_crashed" in readiness.problem
