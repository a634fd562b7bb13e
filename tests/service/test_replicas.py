"""Several ``causalplan serve`` processes on one PostgreSQL: what one replica stores, every replica sees.

Real processes, started as an operator starts them (the ``causalplan`` command, settings from
the environment), on one database: migrations run once when they start together, a
participant's steps go to each in turn, the research-token throttle is one count, a job posted
to one is answered by the other, a load run loses no trial, and a job whose replica is killed
mid-way is finished by another.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import pytest
from sqlalchemy import create_engine, func, select, text
from sqlalchemy.orm import Session

from causalplan.service.storage.migrate import head_revision
from causalplan.service.storage.records import ParticipantRecord, ParticipantTrialRecord, TrialRecord
from tests.conftest import EXAMPLES
from tests.service.fixtures import (
    AUTH,
    DESK_LAMP,
    FLASHLIGHT_MAPPING,
    RESEARCH_TOKEN,
    free_port,
    postgres_database,
)
from tests.service.pages.flows import FLASHLIGHT_CHOICES, LAMP_FUNCTIONS, LAMP_RULES, experiment, links

pytestmark = pytest.mark.slow  # several service replicas over one database

CAUSALPLAN = str(Path(sys.executable).parent / "causalplan")
MAX_FAILURES = 3
LOAD_REQUESTS = 40
LOAD_THREADS = 6


@dataclass
class Replica:
    process: subprocess.Popen[bytes]
    url: str
    log: Path

    def client(self) -> httpx.Client:
        return httpx.Client(base_url=self.url, timeout=60)


def replica_environment(database_url: str, **settings: str) -> dict[str, str]:
    """Return the environment of a replica: the shared database, few workers, quick job polling."""
    environment = {key: value for key, value in os.environ.items() if not key.startswith("CAUSALPLAN_")}
    environment.update(
        {
            "CAUSALPLAN_DATABASE_URL": database_url,
            "CAUSALPLAN_RESEARCH_TOKEN": RESEARCH_TOKEN,
            "CAUSALPLAN_PLANNING_WORKERS": "1",
            "CAUSALPLAN_DRAW_PLANS_AHEAD": "false",
            "CAUSALPLAN_ACCESS_LOG": "false",
            "CAUSALPLAN_JOB_POLL_SECONDS": "0.1",
            "CAUSALPLAN_RESEARCH_MAX_FAILURES": str(MAX_FAILURES),
            "CAUSALPLAN_TRUSTED_PROXIES": '["127.0.0.1"]',  # the tests name clients by X-Forwarded-For
            **{f"CAUSALPLAN_{key.upper()}": value for key, value in settings.items()},
        }
    )
    return environment


def launch(database_url: str, folder: Path, name: str, **settings: str) -> Replica:
    """Start ``causalplan serve`` on a free port (in a session of its own, so its workers can be killed with it)."""
    port = free_port()
    log = folder / f"{name}.log"
    with log.open("wb") as handle:
        process = subprocess.Popen(
            [CAUSALPLAN, "serve", "--host", "127.0.0.1", "--port", str(port)],
            env=replica_environment(database_url, **settings),
            stdout=handle,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
    return Replica(process, f"http://127.0.0.1:{port}", log)


def wait_ready(replica: Replica, seconds: float = 120.0) -> None:
    """Return once the replica is ready (its planner pool has answered a plan); fail if it exits or never is."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        assert replica.process.poll() is None, f"the replica exited:\n{replica.log.read_text()}"
        try:
            if httpx.get(f"{replica.url}/health/ready", timeout=5).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    pytest.fail(f"the replica was not ready within {seconds} s:\n{replica.log.read_text()}")


def stop(replica: Replica, kill: bool = False) -> None:
    """Stop a replica and its planner workers (SIGKILL: as if its machine died)."""
    if replica.process.poll() is None:
        os.killpg(replica.process.pid, signal.SIGKILL if kill else signal.SIGTERM)
        try:
            replica.process.wait(30)
        except subprocess.TimeoutExpired:
            os.killpg(replica.process.pid, signal.SIGKILL)
            replica.process.wait(30)


@contextmanager
def replicas(database_url: str, folder: Path, count: int, **settings: str) -> Iterator[list[Replica]]:
    """Start ``count`` replicas at the same moment on one database; stop them afterwards."""
    with ExitStack() as stack:
        started = [launch(database_url, folder, f"replica-{index}", **settings) for index in range(count)]
        for replica in started:
            stack.callback(stop, replica)
        for replica in started:
            wait_ready(replica)
        yield started


@pytest.fixture(scope="module")
def database(postgres_admin_url: str) -> Iterator[str]:
    with postgres_database(postgres_admin_url) as url:
        yield url


@pytest.fixture(scope="module")
def pair(database: str, tmp_path_factory: pytest.TempPathFactory) -> Iterator[list[Replica]]:
    """Two replicas started together on one empty PostgreSQL database."""
    with replicas(database, tmp_path_factory.mktemp("replicas"), 2) as started:
        yield started


def test_replicas_started_together_migrate_once(pair: list[Replica], database: str) -> None:
    engine = create_engine(database)
    try:
        with engine.connect() as connection:
            assert connection.execute(text("SELECT version_num FROM alembic_version")).scalars().all() == [
                head_revision()
            ]
    finally:
        engine.dispose()
    for replica in pair:
        assert httpx.get(f"{replica.url}/health").json()["database"]["revision"] == head_revision()
        assert "Traceback" not in replica.log.read_text()


def test_a_participants_steps_go_to_each_replica_in_turn(pair: list[Replica], database: str) -> None:
    first, second = (replica.client() for replica in pair)
    with first, second:
        (participant,) = links(first, experiment(second)["id"])
        code = participant["code"]
        steps: list[tuple[httpx.Client, str, dict[str, Any]]] = [
            (first, f"/p/{code}/step1/1", LAMP_FUNCTIONS),
            (second, f"/p/{code}/step2", {"rules": LAMP_RULES}),
            (first, f"/p/{code}/step3/1", FLASHLIGHT_CHOICES),
        ]
        for client, path, form in steps:
            response = client.post(path, data=form, follow_redirects=False)
            assert response.status_code == 303, (path, response.text)
        assert second.get(f"/p/{code}/step3/1").status_code == 200  # the verdict, from the other replica
        assert first.post(f"/p/{code}/step3/1/next", data={}, follow_redirects=False).status_code == 303
    engine = create_engine(database)
    try:
        with Session(engine) as session:
            record = session.scalars(select(ParticipantRecord).where(ParticipantRecord.code == code)).one()
            assert record.finished_at is not None
            linked = select(func.count()).where(ParticipantTrialRecord.participant_id == record.id)
            assert session.scalar(linked) == 1
    finally:
        engine.dispose()


def test_one_address_consenting_on_both_replicas_holds_two_places_and_a_visitor_gets_in(pair: list[Replica]) -> None:
    with pair[0].client() as first:
        created = experiment(first)
    study = created["id"]

    def consent(replica: Replica, address: str, pid: str) -> httpx.Response:
        forwarded = {"X-Forwarded-For": address}
        params = {"PROLIFIC_PID": pid, "STUDY_ID": "s", "SESSION_ID": f"session-{pid}"}
        arrival = httpx.get(f"{replica.url}/s/{study}", params=params, headers=forwarded)
        assert arrival.status_code == 200, arrival.text
        code = re.search(r'name="arrival" value="([A-Za-z0-9]+)"', arrival.text)
        assert code is not None
        form = {"arrival": code.group(1), "decision": "agree"}
        return httpx.post(f"{replica.url}/s/{study}/consent", data=form, headers=forwarded)

    with ThreadPoolExecutor(max_workers=6) as pool:  # at once, on both replicas
        answers = list(pool.map(lambda n: consent(pair[n % 2], "203.0.113.50", f"loop-{n}"), range(6)))
    assert sorted(answer.status_code for answer in answers) == [303, 303, 429, 429, 429, 429]
    assert consent(pair[1], "198.51.100.60", "visitor").status_code == 303


def test_the_research_token_throttle_is_one_count_across_replicas(pair: list[Replica]) -> None:
    guesser = {"X-Forwarded-For": "203.0.113.77"}
    wrong = {**guesser, "Authorization": "Bearer wrong"}
    for attempt in range(MAX_FAILURES):
        replica = pair[attempt % 2]
        assert httpx.get(f"{replica.url}/v1/trials", headers=wrong).status_code == 401
    for replica in pair:  # neither replica answers this client's wrong tokens with 401 any more
        refused = httpx.get(f"{replica.url}/v1/trials", headers=wrong)
        assert refused.status_code == 429 and refused.json()["error"]["code"] == "too_many_attempts"
        # The right token is accepted, from the guessing address too: wrong tokens cost only their sender.
        assert httpx.get(f"{replica.url}/v1/trials", headers={**guesser, **AUTH}).status_code == 200
    assert httpx.get(f"{pair[0].url}/v1/trials", headers=AUTH).status_code == 200  # another client


def test_a_job_posted_to_one_replica_is_followed_on_the_other(pair: list[Replica]) -> None:
    lines = "\n".join((EXAMPLES / "batch" / "trials.jsonl").read_text().splitlines()[:3])
    posted = httpx.post(f"{pair[0].url}/v1/jobs", json={"kind": "batch", "trials": lines, "simulate": False})
    assert posted.status_code == 202
    url = f"{pair[1].url}{posted.json()['url']}"
    job = follow(url)
    assert job["status"] == "succeeded" and job["result"]["trials"] == 3


def follow(url: str, seconds: float = 180.0) -> dict[str, Any]:
    """GET a job until it has finished; return it."""
    deadline = time.monotonic() + seconds
    while True:
        job: dict[str, Any] = httpx.get(url, timeout=30).json()
        if job["status"] not in ("queued", "running"):
            return job
        assert time.monotonic() < deadline, job
        time.sleep(0.2)


def test_a_load_run_over_two_replicas_loses_no_trial(pair: list[Replica], database: str) -> None:
    session_id = f"load-{time.time_ns()}"

    def transfer(number: int) -> str:
        replica = pair[number % 2]
        body = {"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING}
        for _ in range(50):  # a full queue says when to come back: a client that does so loses nothing
            response = httpx.post(
                f"{replica.url}/v1/transfers", json=body, headers={"X-Session-Id": session_id}, timeout=120
            )
            if response.status_code != 429:
                break
            time.sleep(float(response.headers.get("retry-after", "1")))
        assert response.status_code == 200, response.text
        trial_id: str = response.json()["trial_id"]
        return trial_id

    with ThreadPoolExecutor(LOAD_THREADS) as pool:
        answered = list(pool.map(transfer, range(LOAD_REQUESTS)))
    stored = httpx.get(f"{pair[1].url}/v1/trials", params={"session_id": session_id, "limit": 200}, headers=AUTH).json()
    lost = set(answered) - {trial["id"] for trial in stored["data"]}
    assert len(set(answered)) == LOAD_REQUESTS and stored["count"] == LOAD_REQUESTS and lost == set()
    engine = create_engine(database)
    try:
        with Session(engine) as session:
            counted = select(func.count()).where(TrialRecord.session_id == session_id)
            assert session.scalar(counted) == LOAD_REQUESTS
    finally:
        engine.dispose()


def test_a_job_whose_replica_is_killed_is_finished_by_another(postgres_admin_url: str, tmp_path: Path) -> None:
    # Long enough that the kill lands mid-way. The trials differ (one label numbered in each),
    # but equal planning problems under other labels are still answered from the caches: after
    # the first chunk the rest go fast, so it takes many trials for the job to outlast a poll.
    trial = json.dumps({"model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING})
    trials = [
        json.dumps({**json.loads(trial.replace("provide electricity", f"provide electricity {n}")), "id": f"t{n}"})
        for n in range(2000)
    ]
    with postgres_database(postgres_admin_url) as url:
        doomed = launch(url, tmp_path, "doomed", job_lease_seconds="2")
        try:
            wait_ready(doomed)
            body = {"kind": "batch", "trials": "\n".join(trials), "simulate": True}
            job_url = f"{doomed.url}{httpx.post(f'{doomed.url}/v1/jobs', json=body).json()['url']}"
            deadline = time.monotonic() + 120
            while (job := httpx.get(job_url).json())["progress"]["done"] == 0:  # mid-job: a chunk done, more to do
                assert time.monotonic() < deadline and job["status"] in ("queued", "running"), job
                time.sleep(0.05)
            assert job["status"] == "running", job
        finally:
            stop(doomed, kill=True)
        path = job_url.removeprefix(doomed.url)
        with replicas(url, tmp_path, 1, job_lease_seconds="2") as (survivor,):
            job = follow(f"{survivor.url}{path}")
    assert job["status"] == "succeeded" and job["attempts"] == 2, job
    ids = [row["id"] for row in job["result"]["results"]]
    assert len(ids) == len(trials) and len(set(ids)) == len(trials)  # none lost, none counted twice
