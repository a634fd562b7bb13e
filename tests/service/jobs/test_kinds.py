"""The robot's film and the fit estimation as jobs; /health's jobs; each documented example is a job that succeeds.

The film is stored with its job in the database, so an app that only answers (no runner, as
another replica) serves it; cancelling a film stops the worker's filming, not just the job.
"""

from __future__ import annotations

import json
import logging
import uuid
from collections.abc import Iterator
from dataclasses import replace
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner
from distributed import LocalCluster
from fastapi.testclient import TestClient
from sqlalchemy import update
from sqlalchemy.orm import Session

from causalplan.cli import app as cli
from causalplan.consensus.population import population
from causalplan.objects.catalog import load_catalog
from causalplan.service.api.schemas.jobs import JOB_EXAMPLES
from causalplan.service.errors import JobNotFoundError
from causalplan.service.jobs.kinds import CHUNK_SIZE, judge_in_chunks, read_uploaded_trials
from causalplan.service.jobs.work import Progress
from causalplan.service.storage import jobs as store
from causalplan.service.storage.migrate import upgrade
from causalplan.service.storage.records import JobRecord, utc_now
from causalplan.service.storage.session import create_database_engine
from causalplan.service.work.registry import JUDGED_TRIALS
from tests.conftest import EXAMPLES
from tests.service.fixtures import (
    DESK_LAMP,
    KEY_AUTH,
    TEST_CLIENT_OWNER,
    error_of,
    first_trials,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
    wait_until,
)
from tests.service.jobs.test_runner import finished, start
from tests.service.pages.flows import new_participant, post
from tests.service.pool.jobs_for_tests import DyingTrials, judge_or_die

SMALL = {"robot_video_width": 96, "robot_video_height": 72}
"""A small film keeps the tests quick; the robot's run is the same at any size."""


@pytest.fixture(scope="module")
def kinds_database(tmp_path_factory: pytest.TempPathFactory) -> str:
    return sqlite_url(tmp_path_factory.mktemp("db"))


@pytest.fixture(scope="module")
def kinds_client(kinds_database: str) -> Iterator[TestClient]:
    settings = settings_for(kinds_database, job_poll_seconds=0.05, job_lease_seconds=3.0, **SMALL)
    with running_client(settings, KEY_AUTH) as client:  # a key: its jobs a minute are not an anonymous client's few
        yield client


@pytest.fixture(scope="module")
def film(kinds_client: TestClient) -> dict[str, Any]:
    """A finished video job of the desk lamp's model on its own object."""
    job = finished(kinds_client, start(kinds_client, {"kind": "video", "model": DESK_LAMP}), 300.0)
    assert job["status"] == "succeeded", job
    return job


@pytest.mark.slow
def test_a_video_job_films_the_robot_and_serves_the_film(kinds_client: TestClient, film: dict[str, Any]) -> None:
    result = film["result"]
    assert result["planning"]["status"] == "solved"
    assert result["robot"] == {"carried_out": True, "reason": None}
    assert result["video"]["url"] == f"/v1/jobs/{film['id']}/video" and result["video"]["content_type"] == "video/mp4"
    assert film["progress"]["total"] > 1 and film["progress"]["done"] == film["progress"]["total"]  # frames
    served = kinds_client.get(result["video"]["url"])
    assert served.status_code == 200 and served.headers["content-type"] == "video/mp4"
    assert served.content[4:8] == b"ftyp" and len(served.content) == result["video"]["bytes"]


@pytest.mark.slow  # the robot films the lamp (the module's film), and a second replica serves it
def test_another_replica_serves_the_film_from_the_database(kinds_database: str, film: dict[str, Any]) -> None:
    # An app with no runner on the same database: what another replica behind the load balancer is.
    with running_client(settings_for(kinds_database, planning_workers=1, job_runners=0), KEY_AUTH) as other:
        served = other.get(film["result"]["video"]["url"])
        assert served.status_code == 200 and len(served.content) == film["result"]["video"]["bytes"]
        assert other.get(film["url"]).json()["result"]["video"]["url"] == film["result"]["video"]["url"]


@pytest.mark.slow
def test_a_participants_film_asked_of_one_replica_is_followed_and_served_by_another(tmp_path: Path) -> None:
    url = sqlite_url(tmp_path)
    answering = settings_for(url, planning_workers=1, job_runners=0, **SMALL)  # this one cannot film
    filming = settings_for(url, planning_workers=1, job_poll_seconds=0.05, **SMALL)
    with running_client(answering) as first, running_client(filming) as second:
        code = new_participant(first)
        post(first, f"/p/{code}/step1/1", {"part:base_with_cables": "provide electricity", "part:light_bulb": "x"})
        rules = {"rules": "provide electricity AND x CAUSES light"}
        (plan,) = first.post(f"/p/{code}/plan", json=rules).json()["plans"]
        asked = first.post(f"/p/{code}/films", json={"object": "desk_lamp", "fits": plan["fits"]})
        assert asked.status_code == 200, asked.text
        status_url = asked.json()["status_url"]
        wait_until(lambda: second.get(status_url).json()["state"] != "filming", 300.0)
        film = second.get(status_url).json()
        assert film["state"] == "ready" and film["robot"]["carried_out"] is True, film
        assert film["frames"] == film["expected_frames"] and film["bytes"] > 0
        served = first.get(film["video_url"])
        assert served.status_code == 200 and served.headers["content-type"] == "video/mp4"
        assert len(served.content) == film["bytes"]


def test_a_job_without_a_film_says_so(kinds_client: TestClient) -> None:
    job = finished(kinds_client, start(kinds_client, {"kind": "batch", "trials": first_trials(1), "simulate": False}))
    error = error_of(kinds_client.get(f"{job['url']}/video"), 404)
    assert error["code"] == "video_not_found" and error["details"]["kind"] == "batch"
    assert error_of(kinds_client.get(f"/v1/jobs/{uuid.uuid4()}/video"), 404)["code"] == "job_not_found"


@pytest.mark.slow
def test_a_gif_video_job_is_served_as_a_gif(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_poll_seconds=0.05, **SMALL)
    with running_client(settings) as client:
        job = finished(client, start(client, {"kind": "video", "model": DESK_LAMP, "video": "gif"}), 300.0)
        served = client.get(job["result"]["video"]["url"])
        assert served.headers["content-type"] == "image/gif" and served.content[:6] == b"GIF89a"


def test_a_wrong_film_request_is_refused_and_nothing_is_queued(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_runners=0)
    with running_client(settings) as client:
        broken = {**DESK_LAMP, "rules": ["provide electricity CAUSES"]}
        assert (
            error_of(client.post("/v1/jobs", json={"kind": "video", "model": broken}), 422)["code"] == "invalid_model"
        )
        wrong_format = client.post("/v1/jobs", json={"kind": "video", "model": DESK_LAMP, "video": "avi"})
        assert wrong_format.status_code == 422
        filmed_simulation = {"kind": "simulation", "model": DESK_LAMP, "robot": True, "video": "mp4"}
        refused = error_of(client.post("/v1/jobs", json=filmed_simulation), 422)
        assert '"kind": "video"' in refused["message"]
        assert store.count_unfinished(services_of(client).engine) == {"queued": 0, "running": 0}


@pytest.mark.slow
def test_cancelling_a_film_kills_its_worker_before_the_answer(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_poll_seconds=0.05, **SMALL)
    with running_client(settings) as client:
        url = start(client, {"kind": "video", "model": DESK_LAMP, "mapping": None})
        wait_until(lambda: client.get(url).json()["progress"]["total"] > 1, 240.0)  # frames are being drawn
        pool = services_of(client).job_pool
        filming = pool.worker_pids()
        assert client.delete(url).json()["status"] == "cancelled"
        assert pool.stats().busy == 0 and not set(filming) & set(pool.worker_pids())
        job = client.get(url).json()
        assert job["status"] == "cancelled" and job["result"] is None
        assert job["progress"]["done"] < job["progress"]["total"]
        assert error_of(client.get(f"{url}/video"), 404)["code"] == "video_not_found"


# -- fit estimation -----------------------------------------------------------------------------


def cli_estimates(*args: str) -> dict[str, Any]:
    result = CliRunner().invoke(cli, ["estimate-fits", *args, "--json"])
    assert result.exit_code == 0, result.output
    data: dict[str, Any] = json.loads(result.output)
    return data


@pytest.mark.slow
def test_a_fit_estimation_gives_the_numbers_of_the_cli(kinds_client: TestClient) -> None:
    body = {"kind": "fit_estimation", "object": "flashlight", "trials": 30, "seed": 7, "noise_mm": 1.5}
    job = finished(kinds_client, start(kinds_client, body), 300.0)
    assert job["status"] == "succeeded", job
    fits = len(load_catalog(()).get("flashlight").fits)
    assert job["progress"] == {"done": 30 * fits, "total": 30 * fits}  # trials
    expected = cli_estimates("flashlight", "--trials", "30", "--seed", "7", "--noise-mm", "1.5")
    result = job["result"]
    assert {key: result[key] for key in ("object", "noise", "seed", "fits")} == {
        key: expected[key] for key in ("object", "noise", "seed", "fits")
    }
    overlay = result["overlay"]["objects"]["flashlight"]
    assert set(overlay) == {row["id"] for row in expected["fits"]}
    assert result["overlay"]["estimated_by"].startswith("causalplan estimate-fits flashlight --trials 30 --seed 7")


@pytest.mark.slow
def test_a_fit_estimation_on_a_dask_cluster_gives_the_numbers_of_the_cli(tmp_path: Path) -> None:
    with LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=None, silence_logs=logging.ERROR) as cluster:
        settings = settings_for(
            sqlite_url(tmp_path), planning_workers=1, job_poll_seconds=0.05, dask_scheduler=cluster.scheduler_address
        )
        with running_client(settings) as client:
            assert client.get("/health").json()["jobs"]["cluster"] is True
            body = {"kind": "fit_estimation", "object": "flashlight", "trials": 30, "seed": 7, "noise_mm": 1.5}
            job = finished(client, start(client, body), 300.0)
    assert job["status"] == "succeeded", job
    expected = cli_estimates("flashlight", "--trials", "30", "--seed", "7", "--noise-mm", "1.5")
    assert job["result"]["fits"] == expected["fits"]


def test_one_fit_of_an_object_can_be_estimated(kinds_client: TestClient) -> None:
    body = {"kind": "fit_estimation", "object": "flashlight", "trials": 10, "fits": ["head_onto_case"]}
    job = finished(kinds_client, start(kinds_client, body), 300.0)
    assert [row["id"] for row in job["result"]["fits"]] == ["head_onto_case"]
    expected = cli_estimates("flashlight", "--trials", "10", "--fit", "head_onto_case")
    assert job["result"]["fits"] == expected["fits"]


def test_a_wrong_fit_estimation_is_refused_and_nothing_is_queued(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_runners=0, max_job_trials=100)
    with running_client(settings) as client:
        fits = len(load_catalog(()).get("flashlight").fits)
        over = client.post("/v1/jobs", json={"kind": "fit_estimation", "object": "flashlight", "trials": 60})
        assert error_of(over, 422) == {
            "code": "too_many_trials",
            "message": f"{fits} fit(s) of 60 trials each are {fits * 60} trials; "
            "this server takes at most 100 per job.",
            "details": {"limit": 100, "actual": fits * 60},
        }
        unknown_fit = client.post(
            "/v1/jobs", json={"kind": "fit_estimation", "object": "flashlight", "fits": ["head_into_bay"]}
        )
        error = error_of(unknown_fit, 422)
        assert error["details"]["fit"] == "head_into_bay" and "head_onto_case" in error["details"]["fits"]
        unknown_object = client.post("/v1/jobs", json={"kind": "fit_estimation", "object": "flashlite"})
        assert error_of(unknown_object, 404)["code"] == "unknown_object"
        for wrong in ({"trials": 0}, {"noise_mm": -1}, {"noise_deg": 31}, {"fits": [""]}, {"seed": 2**64}):
            body = {"kind": "fit_estimation", "object": "flashlight", **wrong}
            assert client.post("/v1/jobs", json=body).status_code == 422, wrong
        assert store.count_unfinished(services_of(client).engine) == {"queued": 0, "running": 0}


# -- /health and the documented examples --------------------------------------------------------


@pytest.mark.slow
def test_health_counts_the_jobs_of_every_replica_and_this_ones_runners(tmp_path: Path) -> None:
    url = sqlite_url(tmp_path)
    with running_client(settings_for(url, planning_workers=1, job_runners=0)) as client:
        for _ in range(2):
            start(client, {"kind": "batch", "trials": first_trials(1)})
        jobs = client.get("/health").json()["jobs"]
        assert jobs == {
            "queued": 2,
            "running": 0,
            "runners": 0,
            "runners_busy": 0,
            "kinds": ["batch", "simulation", "consensus", "video", "fit_estimation", "troubleshooting"],
            "cluster": False,
            "problem": None,
        }
    with running_client(settings_for(url, planning_workers=1, job_runners=2, job_poll_seconds=0.05)) as client:
        assert client.get("/health").json()["jobs"]["runners"] == 2
        wait_until(lambda: client.get("/health").json()["jobs"]["queued"] == 0, 60.0)  # this replica took them


@pytest.mark.slow
@pytest.mark.parametrize("kind", list(JOB_EXAMPLES))
def test_each_documented_example_is_a_job_that_succeeds(kinds_client: TestClient, kind: str) -> None:
    example = JOB_EXAMPLES[kind]["value"]
    job = finished(kinds_client, start(kinds_client, example), 300.0)
    assert job["status"] == "succeeded" and job["kind"] == kind, job


def test_openapi_documents_each_kind_with_an_example_and_the_video_route(kinds_client: TestClient) -> None:
    document = kinds_client.get("/openapi.json").json()
    body = document["paths"]["/v1/jobs"]["post"]["requestBody"]["content"]["application/json"]
    kinds = {"batch", "simulation", "consensus", "video", "fit_estimation", "troubleshooting"}
    assert set(body["examples"]) == set(JOB_EXAMPLES) == kinds
    video = document["paths"]["/v1/jobs/{job_id}/video"]["get"]["responses"]["200"]["content"]
    assert set(video) == {"video/mp4", "image/gif"}


# -- what the table keeps, on both databases ------------------------------------------------------


def test_a_jobs_file_is_kept_with_it_and_expires_with_it(database_url: str) -> None:
    engine = create_database_engine(database_url)
    upgrade(engine)
    film = bytes(range(256)) * 64  # every byte value: stored as bytes, not text
    job_id = store.create_job(engine, "video", {"video": "mp4"}, 1, 10, owner=TEST_CLIENT_OWNER).id
    assert store.claim_job(engine, "replica-a", 30, ["video"]) is not None
    assert store.get_job_file(engine, job_id) is None  # not made yet
    assert store.finish_job(engine, job_id, "replica-a", 60, result={"video": {}}, file=(film, "video/mp4"))
    assert store.get_job_file(engine, job_id) == (film, "video/mp4")
    assert store.get_job(engine, job_id).file_type == "video/mp4"
    with Session(engine) as session:
        session.execute(
            update(JobRecord).where(JobRecord.id == job_id).values(expires_at=utc_now() - timedelta(seconds=1))
        )
        session.commit()
    with pytest.raises(JobNotFoundError):
        store.get_job_file(engine, job_id)
    assert store.delete_expired(engine) == 1
    with Session(engine) as session:
        assert session.get(JobRecord, job_id) is None
    engine.dispose()


def test_a_failed_job_keeps_no_file(database_url: str) -> None:
    engine = create_database_engine(database_url)
    upgrade(engine)
    job_id = store.create_job(engine, "video", {"video": "mp4"}, 1, 10, owner=TEST_CLIENT_OWNER).id
    assert store.claim_job(engine, "replica-a", 30, ["video"]) is not None
    error = {"code": "x", "message": "failed", "details": {}}
    assert store.finish_job(engine, job_id, "replica-a", 60, error=error, file=(b"half a film", "video/mp4"))
    assert store.get_job_file(engine, job_id) is None
    engine.dispose()


# -- DELETE stops a running job's work ----------------------------------------------------------------


def test_a_cancelled_batch_stops_sending_chunks_to_the_workers(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_poll_seconds=0.05)
    with running_client(settings) as client:
        pool = services_of(client).job_pool
        one = first_trials(1).strip()
        chunks = 20
        url = start(client, {"kind": "batch", "trials": "\n".join([one] * (20 * chunks)), "simulate": True})
        wait_until(lambda: client.get(url).json()["progress"]["done"] >= 20, 120.0)  # a chunk is done
        before = pool.stats().completed
        assert client.delete(url).json()["status"] == "cancelled"
        wait_until(lambda: client.get("/health").json()["jobs"]["runners_busy"] == 0, 120.0)
        # The runner let the job go: at most the chunk in hand (and one that ended as the cancel came), not 18.
        assert pool.stats().completed - before <= 2
        assert client.get(url).json()["status"] == "cancelled"


LONG_WORK = {
    "consensus": {
        "kind": "consensus",
        "trials": "\n".join(json.dumps(line) for line in population("desk_lamp", 400, 1, tests=("flashlight",))),
    },
    "fit_estimation": {"kind": "fit_estimation", "object": "flashlight", "trials": 5000, "fits": ["head_onto_case"]},
    "simulation": {"kind": "simulation", "model": DESK_LAMP, "robot": True},
}
"""Jobs each one call of a worker that runs long (minutes): only killing the worker stops them soon."""


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(LONG_WORK))
def test_deleting_a_running_job_stops_its_worker_before_the_answer(tmp_path: Path, kind: str) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_poll_seconds=0.05)
    with running_client(settings) as client:
        pool = services_of(client).job_pool
        url = start(client, LONG_WORK[kind])
        wait_until(lambda: client.get(url).json()["status"] == "running" and pool.stats().busy == 1, 120.0)
        working = pool.worker_pids()
        assert client.delete(url).json()["status"] == "cancelled"
        # Stopped before DELETE answered: the worker was killed and replaced, none is busy.
        assert pool.stats().busy == 0 and not set(working) & set(pool.worker_pids())
        job = client.get(url).json()
        assert job["status"] == "cancelled" and job["result"] is None


@pytest.mark.slow
def test_a_job_cancelled_through_another_replica_stops_its_worker(tmp_path: Path) -> None:
    database = sqlite_url(tmp_path)
    settings = settings_for(database, planning_workers=1, job_poll_seconds=0.05)
    with running_client(settings) as client:
        pool = services_of(client).job_pool
        url = start(client, LONG_WORK["fit_estimation"])
        wait_until(lambda: pool.stats().busy == 1, 120.0)
        store.cancel_job(services_of(client).engine, uuid.UUID(url.rsplit("/", 1)[1]), 60.0)  # as another would
        # Seen by the runner's heartbeat in the job's row: the worker is killed, the runner free.
        wait_until(lambda: client.get("/health").json()["jobs"]["runners_busy"] == 0, 30.0)
        assert pool.stats().busy == 0
        assert client.get(url).json()["status"] == "cancelled"


def test_a_participants_film_is_found_again_unless_it_failed(tmp_path: Path) -> None:
    engine = create_database_engine(sqlite_url(tmp_path))
    upgrade(engine)
    made = store.create_job(engine, "video", {"film": "k1"}, 1, 10, owner=TEST_CLIENT_OWNER).id
    assert store.find_job(engine, "video", "film", "k2") is None
    found = store.find_job(engine, "video", "film", "k1")
    assert found is not None and found.id == made
    store.cancel_job(engine, made, 60)
    assert store.find_job(engine, "video", "film", "k1") is None  # a cancelled film is filmed again
    engine.dispose()


def test_a_dead_worker_costs_one_chunk_not_the_batch(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_runners=0)
    lines = (EXAMPLES / "batch" / "trials.jsonl").read_text(encoding="utf-8").splitlines()
    trials = read_uploaded_trials("\n".join(lines * 2), 1000)[: 3 * CHUNK_SIZE]
    trials[CHUNK_SIZE + 3] = replace(trials[CHUNK_SIZE + 3], id="die")  # its chunk's worker dies, and its retry's
    trials[2 * CHUNK_SIZE + 5] = replace(trials[2 * CHUNK_SIZE + 5], id="die-once")  # dies once: the retry judges it
    marker = tmp_path / "died-once"
    reported: list[tuple[int, int]] = []
    with running_client(settings) as client:
        services = services_of(client)
        progress = Progress(lambda done, total: reported.append((done, total)))
        dying = replace(JUDGED_TRIALS, name="judge_or_die", function=judge_or_die)
        results = judge_in_chunks(
            services, progress, trials, lambda chunk: DyingTrials(chunk, "fd", 20.0, False, False, str(marker)), dying
        )
    assert [result.trial_id for result in results] == [trial.id for trial in trials]  # every trial, in order
    lost = results[CHUNK_SIZE : 2 * CHUNK_SIZE]
    assert all(result.verdict.verdict.value == "undecided" for result in lost)
    assert all([reason.code for reason in result.verdict.reasons] == ["worker_crashed"] for result in lost)
    assert "died twice" in lost[0].verdict.reasons[0].message
    judged = results[:CHUNK_SIZE] + results[2 * CHUNK_SIZE :]
    assert all(result.verdict.decided_by != "worker" for result in judged)  # kept, and the retried chunk judged
    assert marker.exists() and reported[-1] == (len(trials), len(trials))
