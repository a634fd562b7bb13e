"""A job's work in the jobs' workers: a worker that dies is replaced and the work run once more."""

from __future__ import annotations

from pathlib import Path

import pytest

from causalplan.service.errors import WorkerCrashedError, WorkerDiedError
from causalplan.service.jobs.work import Progress, in_pool_retried
from causalplan.service.work.registry import Pool, Work
from tests.service.fixtures import running_client, services_of, settings_for, sqlite_url
from tests.service.pool.jobs_for_tests import DieOnce, die_once

DIE_ONCE: Work[DieOnce, str] = Work("die_once", die_once, DieOnce, Pool.JOBS, lambda arguments, settings: 60.0)


def test_work_whose_worker_dies_runs_once_more_then_fails(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_runners=1, job_poll_seconds=60)
    marker = tmp_path / "died"
    with running_client(settings) as client:
        services = services_of(client)
        progress = Progress(lambda done, total: None)
        assert in_pool_retried(services, progress, DIE_ONCE, DieOnce(str(marker), "filmed")) == "filmed"
        assert marker.exists()  # the first worker died; its replacement did the work
        with pytest.raises(WorkerCrashedError) as twice:
            in_pool_retried(services, progress, DIE_ONCE, DieOnce("", "never"))
        assert isinstance(twice.value, WorkerDiedError)
        services.job_pool.close()
        with pytest.raises(WorkerCrashedError) as closed:  # a closed pool is no dead worker: not run again
            in_pool_retried(services, progress, DIE_ONCE, DieOnce(str(marker), "never"))
        assert not isinstance(closed.value, WorkerDiedError)
