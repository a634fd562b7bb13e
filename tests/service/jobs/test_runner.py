"""Long work as jobs: POST answers 202 with the job's URL, GET follows it to the result, DELETE cancels.

Also the table's own rules: one claim wins, a lapsed lease is taken over, a job whose server
keeps stopping is given up, and a finished job's result expires.
"""

from __future__ import annotations

import csv
import io
import json
import time
import uuid
from collections.abc import Iterator
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import Engine, update
from sqlalchemy.orm import Session

from causalplan.consensus.population import population
from causalplan.objects.catalog import load_catalog
from causalplan.service.api.schemas.jobs import BatchJobIn
from causalplan.service.jobs.kinds import KINDS, csv_to_json_lines, read_uploaded_trials
from causalplan.service.storage import jobs as store
from causalplan.service.storage.jobs import MAX_ATTEMPTS
from causalplan.service.storage.records import JobRecord, utc_now
from causalplan.service.work.batches import TrialsArguments, judged_trials
from causalplan.transfer.batch import read_trials, run_batch
from tests.service.fixtures import (
    DESK_LAMP,
    FIRST_LINES,
    FLASHLIGHT_MAPPING,
    KEY_AUTH,
    TEST_CLIENT_OWNER,
    error_of,
    first_trials,
    migrated_engine,
    running_client,
    services_of,
    settings_for,
    sqlite_url,
)

KIND_NAMES = list(KINDS)


def as_csv(json_lines: str) -> str:
    out = io.StringIO()
    writer = csv.writer(out)
    writer.writerow(["id", "model", "mapping"])
    for line in json_lines.splitlines():
        entry = json.loads(line)
        writer.writerow([entry["id"], json.dumps(entry["model"]), json.dumps(entry["mapping"])])
    return out.getvalue()


@pytest.fixture(scope="module")
def jobs_client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    settings = settings_for(sqlite_url(tmp_path_factory.mktemp("db")), job_poll_seconds=0.05, job_lease_seconds=3.0)
    with running_client(settings, KEY_AUTH) as client:  # a key: more jobs a minute than a client without one
        yield client


def finished(client: TestClient, url: str, seconds: float = 120.0) -> dict[str, Any]:
    """Follow a job until it has finished; return its last answer."""
    deadline = time.monotonic() + seconds
    while True:
        job: dict[str, Any] = client.get(url).json()
        if job["status"] not in ("queued", "running"):
            return job
        assert time.monotonic() < deadline, f"job still {job['status']} after {seconds} s: {job}"
        time.sleep(0.05)


def start(client: TestClient, body: dict[str, Any]) -> str:
    response = client.post("/v1/jobs", json=body)
    assert response.status_code == 202, response.text
    job = response.json()
    assert response.headers["location"] == job["url"] == f"/v1/jobs/{job['id']}"
    assert job["status"] == "queued" and job["attempts"] == 0 and job["result"] is None
    url: str = job["url"]
    return url


def local_verdicts(json_lines: str, tmp_path: Path) -> dict[str, str]:
    path = tmp_path / "trials.jsonl"
    path.write_text(json_lines, encoding="utf-8")
    results = run_batch(list(read_trials(path)), load_catalog(()), "auto", 20.0, False)
    return {result.trial_id: result.verdict.verdict.value for result in results}


def test_a_batch_job_gives_the_verdicts_of_the_local_batch(jobs_client: TestClient, tmp_path: Path) -> None:
    lines = first_trials()
    url = start(jobs_client, {"kind": "batch", "trials": lines, "simulate": False})
    job = finished(jobs_client, url)
    assert job["status"] == "succeeded", job
    assert job["progress"] == {"done": FIRST_LINES, "total": FIRST_LINES}
    assert job["attempts"] == 1 and job["expires_at"] is not None
    result = job["result"]
    assert result["trials"] == FIRST_LINES
    assert {row["id"]: row["verdict"] for row in result["results"]} == local_verdicts(lines, tmp_path)
    assert sum(result["verdicts"].values()) == FIRST_LINES
    assert result["repeated_ids"] == {}


def test_a_json_lines_upload_that_repeats_ids_is_judged_and_names_them(jobs_client: TestClient) -> None:
    [first, second] = first_trials(2).splitlines()
    lines = "\n".join([first, second, first, first])  # a CSV would be refused; JSON Lines load tests repeat lines
    result = finished(jobs_client, start(jobs_client, {"kind": "batch", "trials": lines, "simulate": False}))["result"]
    assert result["trials"] == 4 and result["repeated_ids"] == {json.loads(first)["id"]: 3}


def test_a_csv_upload_is_the_same_batch(jobs_client: TestClient) -> None:
    lines = first_trials(2)
    by_lines = finished(jobs_client, start(jobs_client, {"kind": "batch", "trials": lines, "simulate": False}))
    by_csv = finished(
        jobs_client, start(jobs_client, {"kind": "batch", "trials": as_csv(lines), "format": "csv", "simulate": False})
    )
    rows = lambda job: [(row["id"], row["verdict"], row["reasons"]) for row in job["result"]["results"]]  # noqa: E731
    assert rows(by_csv) == rows(by_lines) and len(rows(by_lines)) == 2


def test_a_csv_without_its_columns_or_with_a_broken_cell_is_refused_at_once(jobs_client: TestClient) -> None:
    refused = jobs_client.post("/v1/jobs", json={"kind": "batch", "trials": "id,model\n1,{}\n", "format": "csv"})
    assert "no column 'mapping'" in error_of(refused, 422)["message"]
    broken = jobs_client.post(
        "/v1/jobs", json={"kind": "batch", "trials": 'id,model,mapping\n1,{"a": 1},{oops\n', "format": "csv"}
    )
    assert error_of(broken, 422)["details"] == {"row": 2, "column": "mapping"}


def test_a_line_with_a_number_too_long_to_read_is_one_invalid_trial(jobs_client: TestClient) -> None:
    good = first_trials(1)
    too_long = good.rstrip("\n")[:-1] + ', "seed": ' + "7" * 5000 + "}\n"
    job = finished(jobs_client, start(jobs_client, {"kind": "batch", "trials": good + too_long, "simulate": False}))
    rows = job["result"]["results"]
    assert [row["verdict"] for row in rows][1] == "invalid" and rows[1]["reasons"] == "unreadable_trial"
    crowd = finished(
        jobs_client, start(jobs_client, {"kind": "consensus", "trials": good + too_long, "simulate": False})
    )
    assert crowd["status"] == "succeeded", crowd["error"]


def test_a_csv_cell_with_a_number_too_long_is_refused_naming_its_row(jobs_client: TestClient) -> None:
    text = as_csv(first_trials(1)).rstrip("\r\n") + "\n" + 'b,{},"{""seed"": ' + "7" * 5000 + '}"\n'
    refused = jobs_client.post("/v1/jobs", json={"kind": "batch", "trials": text, "format": "csv"})
    assert error_of(refused, 422)["details"] == {"row": 3, "column": "mapping"}


def test_a_csv_with_bare_carriage_returns_and_a_byte_order_mark_keeps_its_ids(jobs_client: TestClient) -> None:
    lines = first_trials(2)
    ids = [json.loads(line)["id"] for line in lines.splitlines()]
    text = "\ufeff" + as_csv(lines).replace("\r\n", "\r")
    job = finished(
        jobs_client, start(jobs_client, {"kind": "batch", "trials": text, "format": "csv", "simulate": False})
    )
    assert [row["id"] for row in job["result"]["results"]] == ids


def test_csv_rows_that_share_an_id_are_refused_naming_it(jobs_client: TestClient) -> None:
    line = first_trials(1)
    trial_id = json.loads(line)["id"]
    refused = jobs_client.post("/v1/jobs", json={"kind": "batch", "trials": as_csv(line + line), "format": "csv"})
    assert error_of(refused, 422)["details"] == {"duplicate_ids": {trial_id: [2, 3]}}


def test_a_batch_job_checks_plans_with_val_by_default_as_the_cli_does(jobs_client: TestClient) -> None:
    services = services_of(jobs_client)
    lines = first_trials(1)
    for body, expected in (
        ({"kind": "batch", "trials": lines}, True),
        ({"kind": "batch", "trials": lines, "validate": False}, False),
    ):
        stored = KINDS["batch"].prepare(BatchJobIn.model_validate(body), services).stored()
        assert stored["validate"] is expected
    arguments = TrialsArguments(tuple(read_uploaded_trials(lines, 1)), "auto", 30.0, False, val=True)
    (checked,) = judged_trials(arguments, services.catalog)
    assert checked.verdict.plan is not None and checked.verdict.plan.validated_by["val"] == "valid"


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"kind": "batch", "trials": "x", "simulate": "false"}, "simulate"),
        ({"kind": "batch", "trials": "x", "time_limit": 1e-6}, "time_limit"),
        ({"kind": "consensus", "trials": "x", "min_support": "0.5"}, "min_support"),
        ({"kind": "fit_estimation", "object": "flashlight", "trials": "5"}, "trials"),
        ({"kind": "fit_estimation", "object": "flashlight", "noise_mm": True}, "noise_mm"),
    ],
)
def test_job_numbers_and_booleans_are_not_coerced_nor_below_their_minimum(
    jobs_client: TestClient, body: dict[str, Any], field: str
) -> None:
    error = error_of(jobs_client.post("/v1/jobs", json=body), 422)
    assert error["code"] == "invalid_request"
    assert [problem["location"] for problem in error["details"]["errors"]] == [f"{body['kind']} > {field}"]


def test_unreadable_lines_are_invalid_trials_as_in_the_cli(jobs_client: TestClient) -> None:
    lines = first_trials(1) + "not json\n"
    job = finished(jobs_client, start(jobs_client, {"kind": "batch", "trials": lines, "simulate": False}))
    verdicts = [row["verdict"] for row in job["result"]["results"]]
    assert len(verdicts) == 2 and verdicts[1] == "invalid"


def test_too_many_trials_are_refused(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, max_job_trials=2, job_runners=0)
    with running_client(settings) as client:
        refused = client.post("/v1/jobs", json={"kind": "batch", "trials": first_trials(3)})
        assert error_of(refused, 422) == {
            "code": "too_many_trials",
            "message": "The upload has 3 trials; this server takes at most 2 per job.",
            "details": {"limit": 2, "actual": 3},
        }


def test_a_simulation_job_gives_the_simulation_and_its_picture(jobs_client: TestClient) -> None:
    body = {"kind": "simulation", "model": DESK_LAMP, "mapping": FLASHLIGHT_MAPPING, "picture": True}
    job = finished(jobs_client, start(jobs_client, body))
    assert job["status"] == "succeeded", job
    result = job["result"]
    assert result["planning"]["status"] == "solved"
    assert result["planning"]["validated_by"] == {"replay": "valid", "val": "valid"}  # VAL by default, as plans
    assert result["simulation"]["produces_goal"] is True
    assert result["image"].startswith("data:image/png;base64,")
    uuid.UUID(result["model_id"])


def test_an_invalid_model_is_refused_before_any_job_is_queued(jobs_client: TestClient) -> None:
    broken = {**DESK_LAMP, "rules": ["provide electricity CAUSES"]}
    refused = jobs_client.post("/v1/jobs", json={"kind": "simulation", "model": broken})
    assert error_of(refused, 422)["code"] == "invalid_model"


@pytest.mark.slow
def test_a_consensus_job_gives_the_report_of_the_cli(jobs_client: TestClient) -> None:
    crowd = "\n".join(json.dumps(line) for line in population("desk_lamp", 6, 1, tests=("flashlight",)))
    job = finished(jobs_client, start(jobs_client, {"kind": "consensus", "trials": crowd, "simulate": False}))
    assert job["status"] == "succeeded", job
    report = job["result"]
    assert report["training_object"] == "desk_lamp" and report["participants"] == 6
    assert "flashlight" in report["mappings"]


def test_a_consensus_of_nobody_fails_and_says_why(jobs_client: TestClient) -> None:
    job = finished(jobs_client, start(jobs_client, {"kind": "consensus", "trials": '{"id": "a", "model": 3}'}))
    assert job["status"] == "failed" and job["result"] is None
    assert job["error"]["code"] == "no_crowd"


def test_a_cancelled_job_stops_and_cannot_be_cancelled_twice(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_runners=0)
    with running_client(settings) as client:  # no runner: the job stays queued until cancelled
        url = start(client, {"kind": "batch", "trials": first_trials(1)})
        cancelled = client.delete(url)
        assert cancelled.status_code == 200 and cancelled.json()["status"] == "cancelled"
        assert client.get(url).json()["status"] == "cancelled"
        assert error_of(client.delete(url), 409)["code"] == "job_finished"


def test_a_running_job_cancelled_stays_cancelled_without_a_result(jobs_client: TestClient) -> None:
    one = first_trials(1).strip()
    lines = "\n".join([one] * 400)  # twenty chunks, each simulated: the cancel comes long before the end
    url = start(jobs_client, {"kind": "batch", "trials": lines, "simulate": True})
    deadline = time.monotonic() + 60
    while jobs_client.get(url).json()["status"] == "queued":
        assert time.monotonic() < deadline
        time.sleep(0.02)
    assert jobs_client.delete(url).json()["status"] == "cancelled"
    time.sleep(1.0)  # the runner's next step sees the cancel; it must not store a result over it
    job = jobs_client.get(url).json()
    assert job["status"] == "cancelled" and job["result"] is None


def test_an_unknown_job_is_404(jobs_client: TestClient) -> None:
    missing = uuid.uuid4()
    assert error_of(jobs_client.get(f"/v1/jobs/{missing}"), 404)["code"] == "job_not_found"
    assert error_of(jobs_client.delete(f"/v1/jobs/{missing}"), 404)["code"] == "job_not_found"


def test_an_unknown_kind_is_refused(jobs_client: TestClient) -> None:
    assert jobs_client.post("/v1/jobs", json={"kind": "robot_video"}).status_code == 422


@pytest.mark.slow
def test_a_finished_job_expires(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_poll_seconds=0.05, job_result_seconds=1.0)
    with running_client(settings) as client:
        url = start(client, {"kind": "batch", "trials": first_trials(1), "simulate": False})
        assert finished(client, url)["status"] == "succeeded"
        time.sleep(1.1)
        assert error_of(client.get(url), 404)["code"] == "job_not_found"
        assert store.delete_expired(services_of(client).engine) == 1


def test_the_queue_of_unfinished_jobs_is_bounded(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_runners=0, max_queued_jobs=2)
    with running_client(settings) as client:
        start(client, {"kind": "batch", "trials": first_trials(1)})
        anonymous = client.post("/v1/jobs", json={"kind": "batch", "trials": first_trials(1)})
        assert error_of(anonymous, 429)["code"] == "too_many_jobs"  # clients without a key: half the cap
        keyed = client.post("/v1/jobs", json={"kind": "batch", "trials": first_trials(1)}, headers=KEY_AUTH)
        assert keyed.status_code == 202, keyed.text  # the other half is the keys'
        refused = client.post("/v1/jobs", json={"kind": "batch", "trials": first_trials(1)}, headers=KEY_AUTH)
        assert error_of(refused, 429)["code"] == "too_many_jobs" and refused.headers["retry-after"] == "30"


def test_uploads_may_be_larger_than_other_bodies(tmp_path: Path) -> None:
    settings = settings_for(sqlite_url(tmp_path), planning_workers=1, job_runners=0, max_body_bytes=2048)
    with running_client(settings) as client:
        lines = first_trials(20)
        assert len(lines) > 2048
        assert client.post("/v1/jobs", json={"kind": "batch", "trials": lines}).status_code == 202
        assert error_of(client.post("/v1/plans", content=b" " * 4096), 413)["details"] == {"limit": 2048}


# -- the table's rules --------------------------------------------------------------------------


@pytest.fixture
def engine(tmp_path: Path) -> Engine:
    return migrated_engine(tmp_path)


def queued(engine: Engine) -> uuid.UUID:
    request = {"trials": first_trials(1), "count": 1, "planner": "auto", "time_limit": 20.0, "simulate": False}
    return store.create_job(engine, "batch", request, 1, 10, owner=TEST_CLIENT_OWNER).id


def lapse(engine: Engine, job_id: uuid.UUID) -> None:
    """Make the job's lease lapse, as when its server died."""
    with Session(engine) as session:
        session.execute(
            update(JobRecord).where(JobRecord.id == job_id).values(lease_expires_at=utc_now() - timedelta(seconds=1))
        )
        session.commit()


def test_of_two_claims_on_one_job_one_wins(engine: Engine) -> None:
    job_id = queued(engine)
    first = store.claim_job(engine, "replica-a", 30, KIND_NAMES)
    assert first is not None and first.id == job_id and first.lease_owner == "replica-a"
    assert store.claim_job(engine, "replica-b", 30, KIND_NAMES) is None
    assert not store.renew_lease(engine, job_id, "replica-b", 30)
    assert not store.finish_job(engine, job_id, "replica-b", 60, result={"x": 1})
    assert store.finish_job(engine, job_id, "replica-a", 60, result={"x": 1})


def test_a_lapsed_lease_is_taken_over_and_the_old_owner_cannot_write(engine: Engine) -> None:
    job_id = queued(engine)
    assert store.claim_job(engine, "dead", 30, KIND_NAMES) is not None
    lapse(engine, job_id)
    taken = store.claim_job(engine, "alive", 30, KIND_NAMES)
    assert taken is not None and taken.attempts == 2 and taken.lease_owner == "alive"
    assert not store.finish_job(engine, job_id, "dead", 60, result={"late": True})
    assert store.finish_job(engine, job_id, "alive", 60, result={"ok": True})
    assert store.get_job(engine, job_id).result == {"ok": True}


def test_a_job_whose_server_keeps_stopping_is_given_up(engine: Engine) -> None:
    job_id = queued(engine)
    for attempt in range(MAX_ATTEMPTS):
        assert store.claim_job(engine, f"replica-{attempt}", 30, KIND_NAMES) is not None
        lapse(engine, job_id)
    assert store.claim_job(engine, "last", 30, KIND_NAMES) is None
    job = store.get_job(engine, job_id)
    assert job.status == "failed" and job.error is not None and job.error["code"] == "job_abandoned"
    assert job.expires_at is not None  # kept as long as any finished job, then deleted


def test_a_replica_takes_up_the_job_of_one_that_died(tmp_path: Path) -> None:
    url = sqlite_url(tmp_path)
    engine = migrated_engine(tmp_path)
    job_id = queued(engine)
    assert store.claim_job(engine, "died-mid-job", 30, KIND_NAMES) is not None
    lapse(engine, job_id)
    with running_client(settings_for(url, planning_workers=1, job_poll_seconds=0.05)) as client:
        job = finished(client, f"/v1/jobs/{job_id}")
    assert job["status"] == "succeeded" and job["attempts"] == 2


def test_a_replica_that_stops_puts_its_job_back(engine: Engine) -> None:
    job_id = queued(engine)
    assert store.claim_job(engine, "stopping", 30, KIND_NAMES) is not None
    store.release_job(engine, job_id, "stopping")
    job = store.get_job(engine, job_id)
    assert (job.status, job.lease_owner, job.attempts) == ("queued", None, 0)


def test_a_job_of_a_kind_this_server_cannot_do_is_left_for_others(engine: Engine) -> None:
    store.create_job(engine, "robot_video", {}, 1, 10, owner=TEST_CLIENT_OWNER)
    assert store.claim_job(engine, "older", 30, KIND_NAMES) is None


def test_csv_rows_become_json_lines() -> None:
    text = 'id,model,mapping\nt1,"{""object"": ""desk_lamp""}","{""object"": ""flashlight""}"\n,{},{}\n'
    assert [json.loads(line) for line in csv_to_json_lines(text).splitlines()] == [
        {"id": "t1", "model": {"object": "desk_lamp"}, "mapping": {"object": "flashlight"}},
        {"id": "row-3", "model": {}, "mapping": {}},
    ]
