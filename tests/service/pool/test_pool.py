"""The planner pool under load and faults: 429 when full, killed and stuck workers, bugs; the cache."""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi.testclient import TestClient

from causalplan.causal.documents import SourceMap
from causalplan.inputs import model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.service import main
from causalplan.service.errors import PlanningTimeoutError, QueueFullError, StorageError, WorkerCrashedError
from causalplan.service.jobs.work import Progress, in_pool
from causalplan.service.pool.pool import PlannerPool, RunStoppedError
from causalplan.service.pool.worker import FOLDER_PREFIX
from causalplan.service.work.calls import ResultCache, answer_key, canonical_key
from causalplan.service.work.planning import PlanArguments
from causalplan.service.work.registry import PLAN, Pool, Work
from tests.service.fixtures import (
    DESK_LAMP,
    error_of,
    is_running,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
    wait_until,
    with_unique_effect,
)
from tests.service.pool.jobs_for_tests import (
    RELEASE_VARIABLE,
    STARTED_MARK,
    allocate_too_much,
    crash_with_exception,
    plan_when_released,
    sleep_forever,
    start_a_session_then_hang,
    temp_folders,
    timed_sleep,
)


@pytest.fixture(scope="module")
def release(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The file whose creation lets ``plan_when_released`` solve (a test removes it first)."""
    return tmp_path_factory.mktemp("release") / "release"


@pytest.fixture(scope="module")
def one_worker(tmp_path_factory: pytest.TempPathFactory, release: Path) -> Iterator[TestClient]:
    """An app with one planner worker and no queue: a second solve at once is refused."""
    settings = settings_for(
        sqlite_url(tmp_path_factory.mktemp("db")), planning_workers=1, queue_size=0, solve_grace_seconds=1.0
    )
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(RELEASE_VARIABLE, str(release))  # before the app starts: its workers take its environment
        with running_client(settings) as client:
            yield client


def post_in_background(client: TestClient, body: dict[str, Any]) -> tuple[threading.Thread, list[httpx.Response]]:
    """Post a plan request from another thread; return the thread and where its response lands."""
    responses: list[httpx.Response] = []
    thread = threading.Thread(target=lambda: responses.append(client.post("/v1/plans", json=body)))
    thread.start()
    return thread, responses


@pytest.mark.slow
def test_a_full_queue_is_429_with_retry_after(
    one_worker: TestClient, release: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pool = services_of(one_worker).pool
    answered = {"model": with_unique_effect(DESK_LAMP)}
    assert one_worker.post("/v1/plans", json=answered).status_code == 200
    release.unlink(missing_ok=True)
    monkeypatch.setattr(PLAN, "function", plan_when_released)  # the worker stays busy until released
    thread, responses = post_in_background(one_worker, {"model": with_unique_effect(DESK_LAMP)})
    wait_until(lambda: pool.stats().busy == 1)
    refused = one_worker.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)})
    error = error_of(refused, 429)
    assert error["code"] == "queue_full"
    assert int(refused.headers["Retry-After"]) >= 1
    assert error["details"]["retry_after"] == int(refused.headers["Retry-After"])
    # Answers from the cache need no worker, so they are not refused.
    repeated = one_worker.post("/v1/plans", json=answered)
    assert repeated.status_code == 200 and repeated.json()["cached"] is True
    assert pool.stats().busy == 1  # still the first request's solve
    release.touch()
    thread.join()
    assert responses[0].status_code == 200 and responses[0].json()["status"] == "solved"


def test_a_killed_worker_fails_only_its_request(
    one_worker: TestClient, release: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pool = services_of(one_worker).pool
    release.unlink(missing_ok=True)  # never released: the worker is killed while it waits
    monkeypatch.setattr(PLAN, "function", plan_when_released)
    [pid] = pool.worker_pids()
    (_temp_folder_of(pid) / STARTED_MARK).unlink(missing_ok=True)  # left by an earlier slow job of this worker
    thread, responses = post_in_background(one_worker, {"model": with_unique_effect(DESK_LAMP)})
    # Killed once the job has begun: a worker killed before it takes its job hands the job on (200).
    wait_until(lambda: (_temp_folder_of(pid) / STARTED_MARK).exists())
    os.kill(pid, signal.SIGKILL)
    thread.join()
    error = error_of(responses[0], 503)
    assert error["code"] == "planner_crashed"
    assert error["details"]["exit_code"] == -signal.SIGKILL
    assert responses[0].headers["Retry-After"] == "1"
    monkeypatch.undo()
    after = one_worker.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)})
    assert after.status_code == 200 and after.json()["status"] == "solved"
    assert pool.worker_pids() != [pid] and pool.stats().replaced >= 1


def test_a_worker_killed_while_idle_is_replaced_before_use(one_worker: TestClient) -> None:
    pool = services_of(one_worker).pool
    [pid] = pool.worker_pids()
    os.kill(pid, signal.SIGKILL)
    wait_until(lambda: not is_running(pid))
    response = one_worker.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)})
    assert response.status_code == 200 and response.json()["status"] == "solved"


def test_a_stuck_worker_is_killed_after_its_time_limit(one_worker: TestClient, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(PLAN, "function", sleep_forever)
    response = one_worker.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP), "time_limit": 0.5})
    error = error_of(response, 504)
    assert error["code"] == "planning_timeout"
    assert error["details"] == {"seconds": 1.5}
    monkeypatch.undo()
    after = one_worker.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)})
    assert after.status_code == 200 and after.json()["status"] == "solved"


def test_a_bug_in_a_job_is_500_without_a_traceback(one_worker: TestClient, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(PLAN, "function", crash_with_exception)
    error = error_of(one_worker.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)}), 500)
    assert error["code"] == "internal_error"
    assert "a bug in a planner" not in error["message"]
    monkeypatch.undo()
    assert one_worker.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)}).status_code == 200


def test_a_worker_out_of_memory_is_503_and_keeps_serving(
    one_worker: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(PLAN, "function", allocate_too_much)
    error = error_of(one_worker.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)}), 503)
    assert error["code"] == "planner_out_of_memory"
    monkeypatch.undo()
    assert one_worker.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)}).status_code == 200


@pytest.mark.slow
def test_a_missing_planner_binary_is_reported_and_planning_still_answers(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("CAUSALPLAN_FD_BINARY", str(tmp_path / "no-such-downward"))  # the workers inherit it
    with main._probe_lock:  # an earlier server's probe, still running, would store its answer over this one's
        monkeypatch.setattr(main, "_probe_result", None)  # probe this server's workers afresh (restored after)
    with running_client(settings_for(f"sqlite:///{tmp_path}/db.sqlite3", planning_workers=1)) as client:
        health = client.get("/health").json()
        assert health["status"] == "degraded"
        assert health["fast_downward"]["available"] is False
        assert "no-such-downward" in health["fast_downward"]["problem"]
        assert str(tmp_path) not in str(health)  # only what is wrong, never the binary's whole path
        fd = next(planner for planner in health["planners"] if planner["name"] == "fd")
        assert fd["available"] is False and fd["problem"]
        body = client.post("/v1/plans", json={"model": DESK_LAMP, "planner": "fd"}).json()
        assert body["status"] == "error" and "no-such-downward" in body["message"]


@pytest.mark.slow
def test_a_full_queue_with_a_waiting_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    settings = settings_for(f"sqlite:///{tmp_path}/db.sqlite3", planning_workers=1, queue_size=1)
    release = tmp_path / "release"
    monkeypatch.setenv(RELEASE_VARIABLE, str(release))  # before the app starts: its workers take its environment
    with running_client(settings) as client:
        pool = services_of(client).pool
        monkeypatch.setattr(PLAN, "function", plan_when_released)  # the worker stays busy until released
        running = post_in_background(client, {"model": with_unique_effect(DESK_LAMP)})
        wait_until(lambda: pool.stats().busy == 1)
        waiting = post_in_background(client, {"model": with_unique_effect(DESK_LAMP)})
        # The waiting line is the fair share's, in front of the pool (service/fair_share.py).
        wait_until(lambda: pool.fair_share.stats()["waiting"] == 1)
        assert pool.stats().waiting == 1  # what /health shows of the interactive pool
        assert error_of(client.post("/v1/plans", json={"model": with_unique_effect(DESK_LAMP)}), 429)
        release.touch()
        for thread, responses in (running, waiting):
            thread.join()
            assert responses[0].status_code == 200


def test_the_cache_keeps_the_most_recently_used() -> None:
    cache = ResultCache(2)
    for key in ("a", "b"):
        cache.put(key, {"key": key})
    assert cache.get("a") == {"key": "a"}
    cache.put("c", {"key": "c"})
    assert cache.get("b") is None and cache.get("a") is not None and cache.get("c") is not None
    copy = cache.get("a")
    assert copy is not None
    copy["key"] = "changed"
    assert cache.get("a") == {"key": "a"}
    assert cache.stats() == {"size": 2, "entries": 2, "hits": 5, "misses": 1}
    ResultCache(0).put("x", {})


def test_canonical_keys_ignore_layout_but_not_meaning(catalog: Catalog) -> None:
    def model(data: dict[str, Any]) -> Any:
        loaded = model_from_data(data, SourceMap(), catalog)
        assert loaded.is_valid, loaded.report.as_dict()
        return loaded.model

    base = model(DESK_LAMP)
    layout = model({**DESK_LAMP, "rules": [r.replace(" AND ", " and  ") for r in reversed(DESK_LAMP["rules"])]})
    other = model({**DESK_LAMP, "goal": "Light"})

    def request_key(kind: str, model: Any, planner: str, limit: float, catalog: str) -> str:
        return answer_key(kind, canonical_key(PlanArguments(model, None, planner, limit)), catalog)

    key = request_key("plan", base, "fd", 30.0, "catalog")
    assert key == request_key("plan", layout, "fd", 30.0, "catalog")
    assert key != request_key("plan", base, "fd-opt", 30.0, "catalog")
    assert key != request_key("transfer", base, "fd", 30.0, "catalog")
    assert key != request_key("plan", other, "fd", 30.0, "catalog")  # answers quote it
    assert key != request_key("plan", base, "fd", 5.0, "catalog")
    assert key != request_key("plan", base, "fd", 30.0, "another catalog")


@contextmanager
def bare_pool(size: int) -> Iterator[PlannerPool]:
    """Start a bare pool of ``size`` workers and no waiting line; close it afterwards."""
    pool = PlannerPool(size, 0, settings_for("sqlite://").worker_memory_mb, queue_wait_seconds=5.0)
    pool.start()
    try:
        yield pool
    finally:
        pool.close()


@pytest.fixture(scope="module")
def two_workers() -> Iterator[PlannerPool]:
    """A bare pool of two workers and no waiting line."""
    with bare_pool(2) as pool:
        yield pool


def test_meanwhile_runs_while_the_worker_works(two_workers: PlannerPool) -> None:
    ran: list[tuple[float, int]] = []
    _, ended, _ = two_workers.run(
        timed_sleep, (0.5,), 30, meanwhile=lambda: ran.append((time.monotonic(), two_workers.stats().busy))
    )
    [(at, busy)] = ran
    assert busy == 1 and at < ended  # once a worker had the job, before it had done it


def test_what_meanwhile_raises_comes_after_the_answer_and_the_worker_stays_in_step(two_workers: PlannerPool) -> None:
    def broken() -> None:
        raise StorageError("the database is gone")

    with pytest.raises(StorageError, match="the database is gone"):
        two_workers.run(timed_sleep, (0.1,), 30, meanwhile=broken)
    assert two_workers.stats().busy == 0
    # The failed request's reply was read: the next job gets its own answer, not that one.
    began, ended, _ = two_workers.run(timed_sleep, (0.2,), 30)
    assert ended - began >= 0.2


def test_a_refused_request_runs_nothing_meanwhile() -> None:
    with bare_pool(1) as pool:
        busy = threading.Thread(target=pool.run, args=(timed_sleep, (1.0,), 30))
        busy.start()
        wait_until(lambda: pool.stats().busy == 1)
        ran: list[bool] = []
        with pytest.raises(QueueFullError):
            pool.run(timed_sleep, (0.0,), 30, meanwhile=lambda: ran.append(True))
        busy.join()
        assert ran == []


@pytest.mark.slow
def test_a_killed_worker_leaves_no_temp_folders_behind() -> None:
    with bare_pool(1) as pool:
        first, search = pool.run(temp_folders, (), 30)
        assert Path(first).name.startswith(FOLDER_PREFIX) and Path(first).is_dir()
        assert Path(search).parent == Path(first) and Path(search).is_dir()
        with pytest.raises(PlanningTimeoutError):
            pool.run(sleep_forever, (), 0.5)  # the pool SIGKILLs the worker: its atexit never runs
        assert not Path(first).exists()
        second, _ = pool.run(temp_folders, (), 30)  # the replacement has a folder of its own
        assert second != first and Path(second).is_dir()
    assert not Path(second).exists()


def _temp_folder_of(pid: int) -> Path:
    """Return the temp folder (TMPDIR) of worker ``pid``: ``causalplan-worker-<app pid>-<worker pid>-<random>``."""
    [folder] = Path(tempfile.gettempdir()).glob(f"{FOLDER_PREFIX}*-{pid}-*")
    return folder


def test_closing_a_pool_removes_its_workers_temp_folders() -> None:
    errors: list[BaseException] = []

    def run_stuck_job() -> None:
        try:
            pool.run(sleep_forever, (), 30)
        except Exception as exc:  # noqa: BLE001 - checked below: the closing pool kills this worker
            errors.append(exc)

    busy = threading.Thread(target=run_stuck_job)
    with bare_pool(2) as pool:  # closing it stops the idle worker and kills the busy one
        folders = [_temp_folder_of(pid) for pid in pool.worker_pids()]
        assert len(folders) == 2 and all(folder.name.startswith("causalplan-worker-") for folder in folders)
        assert all(folder.is_dir() for folder in folders)
        busy.start()
        wait_until(lambda: pool.stats().busy == 1)
    busy.join()
    assert len(errors) == 1  # the stuck job did not answer: its worker was killed
    assert not any(folder.exists() for folder in folders)


@pytest.mark.slow
def test_a_killed_worker_takes_its_own_sessions_children_with_it(tmp_path: Path) -> None:
    pid_file = tmp_path / "child.pid"
    with bare_pool(1) as pool, pytest.raises(PlanningTimeoutError):
        pool.run(start_a_session_then_hang, (str(pid_file),), 2.0)
    child = int(pid_file.read_text())
    wait_until(lambda: not is_running(child))  # an orphan, reaped by init once it is killed


def test_a_job_that_cannot_be_sent_fails_alone_and_the_pool_keeps_its_workers(two_workers: PlannerPool) -> None:
    with pytest.raises(Exception, match="pickle"):
        two_workers.run(timed_sleep, (lambda: None,), 30)  # a lambda cannot be pickled
    assert len(two_workers.worker_pids()) == 2
    answers: list[tuple[float, float, int]] = []
    both = [threading.Thread(target=lambda: answers.append(two_workers.run(timed_sleep, (0.5,), 30))) for _ in range(2)]
    for thread in both:
        thread.start()
    for thread in both:
        thread.join()
    # Two jobs at once, each on its own worker: neither worker was lost (a lost one leaves the second waiting, refused).
    assert len({pid for _, _, pid in answers}) == 2
    assert two_workers.stats().busy == 0


def test_a_worker_that_dies_before_taking_its_job_hands_it_to_its_replacement() -> None:
    # A stopped worker cannot take the job sent to it; killed then, with no job begun, pebble takes
    # its whole pool for broken: the job must still be answered, by a new worker.
    with bare_pool(1) as pool:
        [pid] = pool.worker_pids()
        os.kill(pid, signal.SIGSTOP)
        answers: list[tuple[float, float, int]] = []
        job = threading.Thread(target=lambda: answers.append(pool.run(timed_sleep, (0.0,), 30)))
        job.start()
        wait_until(lambda: pool.stats().busy == 1)
        os.kill(pid, signal.SIGKILL)
        job.join()
        [(_, _, answered_by)] = answers
        assert answered_by != pid and pool.worker_pids() == [answered_by]
        assert pool.stats().replaced == 1


def _dead_pid() -> int:
    process = subprocess.Popen(["true"])
    process.wait()
    return process.pid


def test_starting_a_pool_removes_folders_left_by_a_killed_server() -> None:
    root = Path(tempfile.gettempdir())
    stale = root / f"{FOLDER_PREFIX}{_dead_pid()}-left"
    (stale / "causalplan-fd-search").mkdir(parents=True)
    live = Path(tempfile.mkdtemp(prefix=f"{FOLDER_PREFIX}{os.getpid()}-"))  # this process's: in use
    try:
        with bare_pool(1):
            assert not stale.exists()
            assert live.is_dir()
    finally:
        live.rmdir()


def test_a_server_killed_with_sigkill_leaves_folders_the_next_start_removes(tmp_path: Path) -> None:
    # Both servers are processes of their own with a temp root of their own: a sweep in this
    # process (any pool's start, close or killed worker, from another test's thread) never
    # sees the folder, and no process-wide ``tempfile.tempdir`` is patched under other threads.
    environment = {**os.environ, "TMPDIR": str(tmp_path)}
    start = "from causalplan.service.pool.pool import PlannerPool; pool = PlannerPool(1, 0, 4096, 5.0); pool.start()"
    server = subprocess.Popen(
        [sys.executable, "-c", f"import time; {start}; print(pool.worker_pids()[0], flush=True); time.sleep(600)"],
        stdout=subprocess.PIPE,
        text=True,
        env=environment,
    )
    assert server.stdout is not None
    worker_pid = int(server.stdout.readline())
    [folder] = tmp_path.glob(f"{FOLDER_PREFIX}*-{worker_pid}-*")
    server.kill()
    server.wait()
    os.kill(worker_pid, signal.SIGKILL)  # its worker would notice the closed socket only when it next reads
    wait_until(lambda: not is_running(worker_pid))
    assert folder.is_dir()  # nobody was left to remove it
    next_start = f"import pathlib; {start}; print(pathlib.Path({str(folder)!r}).exists(), flush=True); pool.close()"
    after = subprocess.run(
        [sys.executable, "-c", next_start], capture_output=True, text=True, env=environment, check=True
    )
    assert after.stdout.split() == ["False"]


def _parent_of(pid: int) -> int:
    return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])


def test_workers_are_not_forks_of_the_app(two_workers: PlannerPool) -> None:
    # The app runs uvicorn's and anyio's threads: its workers come from a fork server.
    assert len(two_workers.worker_pids()) == 2
    assert all(_parent_of(pid) != os.getpid() for pid in two_workers.worker_pids())


def test_a_stopped_run_kills_its_worker_and_its_sessions_children_before_it_returns(tmp_path: Path) -> None:
    pid_file = tmp_path / "child.pid"
    stop = threading.Event()
    with bare_pool(1) as pool:
        [worker] = pool.worker_pids()
        threading.Thread(target=lambda: (wait_until(pid_file.exists), stop.set())).start()
        with pytest.raises(RunStoppedError):
            pool.run(start_a_session_then_hang, (str(pid_file),), 60, stop=stop)
        assert not is_running(worker) and pool.stats().busy == 0
        assert worker not in pool.worker_pids()
        child = int(pid_file.read_text())
        wait_until(lambda: not is_running(child), 5.0)  # killed by its worker; reaped by init
        wait_until(lambda: len(pool.worker_pids()) == 1)  # replaced
        assert pool.run(timed_sleep, (0.0,), 30)[2] != worker


def test_a_closed_pool_answers_503_and_a_job_stops_trying(one_worker: TestClient) -> None:
    closed = PlannerPool(1, 0, settings_for("sqlite://").worker_memory_mb, queue_wait_seconds=5.0)
    closed.close()
    with pytest.raises(WorkerCrashedError):
        closed.run(timed_sleep, (0.0,), 30)
    # A job's call gives up at once: it used to take the closed pool for a full one and retry forever.
    running = services_of(one_worker)
    services = dataclasses.replace(running, work=dataclasses.replace(running.work, jobs=closed))
    never_runs = Work("sleep", crash_with_exception, float, Pool.JOBS, lambda arguments, settings: 30.0)
    raised: list[BaseException] = []

    def call() -> None:
        try:
            in_pool(services, Progress(lambda done, total: None), never_runs, 0.0)
        except Exception as exc:  # noqa: BLE001 - checked below
            raised.append(exc)

    caller = threading.Thread(target=call, daemon=True)
    caller.start()
    caller.join(10)
    assert not caller.is_alive() and isinstance(raised[0], WorkerCrashedError)


def test_health_shows_both_pools(one_worker: TestClient) -> None:
    health = one_worker.get("/health").json()
    assert health["pool"]["workers"] == 1 and health["pool"]["max_in_flight"] == 1
    services = services_of(one_worker)
    assert health["job_pool"]["workers"] == services.settings.job_runners == services.job_pool.size
    assert health["job_pool"]["max_in_flight"] == services.job_pool.size
