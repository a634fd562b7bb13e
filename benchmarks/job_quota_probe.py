"""What one anonymous client can make the jobs table hold: the issue's probe, run the same way before and after.

Three parts, each on a fresh SQLite database (an app through TestClient, one job runner):

1. tiny jobs: ``POST /v1/jobs`` with a one-line batch (one invalid trial) as fast as one client
   can for ``--seconds``; reports the jobs accepted per minute and the refusals by code;
2. big bodies: ``--bodies`` posts of ~15.7 MB, one invalid trial each; reports the statuses, the
   megabytes the jobs keep (requests and results) and how much the database (file and
   write-ahead log) grew: more than the jobs keep, as SQLite keeps the pages a row's rewrite
   freed (a job's row is rewritten when it is claimed and finished);
3. the cap: ``--threads`` clients post at once against ``max_queued_jobs`` = ``--cap`` (nothing
   runs the jobs); reports the most unfinished jobs seen against the cap.

Only the HTTP API and ``Settings`` are used, so the same script measures any checkout:
``PYTHONPATH=/path/to/checkout python benchmarks/job_quota_probe.py``. Settings an older
checkout does not know are ignored there.
"""

from __future__ import annotations

import argparse
import collections
import json
import sqlite3
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from fastapi.testclient import TestClient

from causalplan.service.main import create_app
from causalplan.settings import Settings

TINY = {"kind": "batch", "trials": "not a trial\n", "simulate": False}
BIG_BODY_BYTES = 15_700_000


def _settings(folder: Path, **overrides: Any) -> Settings:
    values: dict[str, Any] = {
        "database_url": f"sqlite:///{folder / 'probe.sqlite3'}",
        "data_folder": folder,
        "planning_workers": 1,
        "job_runners": 1,
        "draw_plans_ahead": False,
        "access_log": False,
        **overrides,
    }
    return Settings(**values)


def _database_bytes(folder: Path) -> int:
    return sum(path.stat().st_size for path in folder.glob("probe.sqlite3*"))


def _code(response: Any) -> str:
    if response.status_code < 400:
        return str(response.status_code)
    try:
        return f"{response.status_code} {response.json()['error']['code']}"
    except (ValueError, KeyError):
        return str(response.status_code)


def _drain(client: TestClient, seconds: float = 300.0) -> None:
    """Wait until the runner has finished every job (the app then stops without killing a worker mid-job)."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        jobs = client.get("/health").json()["jobs"]
        if jobs["queued"] + jobs["running"] == 0:
            return
        time.sleep(0.2)


def tiny_jobs(seconds: float) -> dict[str, Any]:
    """Post tiny jobs for ``seconds``; return the jobs accepted a minute and the answers by code."""
    with (
        tempfile.TemporaryDirectory(prefix="job-probe-") as name,
        TestClient(create_app(_settings(Path(name))), raise_server_exceptions=False) as client,
    ):
        answers: collections.Counter[str] = collections.Counter()
        retry_after: set[str] = set()
        began = time.monotonic()
        while time.monotonic() - began < seconds:
            response = client.post("/v1/jobs", json=TINY)
            answers[_code(response)] += 1
            if response.status_code == 429:
                retry_after.add(response.headers.get("retry-after", "missing"))
        elapsed = time.monotonic() - began
        _drain(client)
    accepted = answers["202"]
    return {
        "seconds": round(elapsed, 1),
        "posted": sum(answers.values()),
        "accepted": accepted,
        "accepted_per_minute": round(accepted * 60 / elapsed),
        "answers": dict(answers),
        "retry_after_seen": sorted(retry_after)[:5],
    }


def big_bodies(count: int) -> dict[str, Any]:
    """Post ``count`` bodies of ~15.7 MB (one invalid trial each); return the answers and the database's growth."""
    line = "x" * (BIG_BODY_BYTES - 64) + "\n"  # not JSON: one invalid trial
    body = json.dumps({"kind": "batch", "trials": line, "simulate": False}).encode()
    with (
        tempfile.TemporaryDirectory(prefix="job-probe-") as name,
        TestClient(create_app(_settings(Path(name))), raise_server_exceptions=False) as client,
    ):
        folder = Path(name)
        before = _database_bytes(folder)
        answers: collections.Counter[str] = collections.Counter()
        for _ in range(count):
            response = client.post("/v1/jobs", content=body, headers={"Content-Type": "application/json"})
            answers[_code(response)] += 1
        _drain(client)
        after = _database_bytes(folder)
        kept = _jobs_bytes(folder)
    return {
        "body_mb": round(len(body) / 1e6, 1),
        "posted": count,
        "answers": dict(answers),
        "jobs_keep_mb": round(kept / 1e6, 1),
        "database_mb_before": round(before / 1e6, 1),
        "database_mb_after": round(after / 1e6, 1),
        "grew_mb": round((after - before) / 1e6, 1),
    }


def _jobs_bytes(folder: Path) -> int:
    """Return the bytes of the jobs' requests and results in the database (as SQLite stores the JSON text)."""
    with sqlite3.connect(folder / "probe.sqlite3") as connection:
        row = connection.execute("SELECT SUM(LENGTH(request) + COALESCE(LENGTH(result), 0)) FROM jobs").fetchone()
    return int(row[0] or 0)


def cap_race(cap: int, threads: int, posts: int, rounds: int = 3) -> dict[str, Any]:
    """Post from ``threads`` clients at once against a cap of ``cap`` unfinished jobs; return the most seen."""
    worst = 0
    for _ in range(rounds):
        # The clients' own limits are lifted (an older checkout ignores settings it does not know).
        with tempfile.TemporaryDirectory(prefix="job-probe-") as name:
            settings = _settings(
                Path(name),
                job_runners=0,
                max_queued_jobs=cap,
                anonymous_jobs_in_flight=100_000,
                anonymous_jobs_per_minute=0,
            )
            with TestClient(create_app(settings), raise_server_exceptions=False) as client:
                start = threading.Barrier(threads)

                def post(client: TestClient = client, start: threading.Barrier = start) -> None:
                    start.wait()
                    for _ in range(posts):
                        client.post("/v1/jobs", json=TINY)

                workers = [threading.Thread(target=post) for _ in range(threads)]
                for worker in workers:
                    worker.start()
                for worker in workers:
                    worker.join()
                worst = max(worst, int(client.get("/health").json()["jobs"]["queued"]))
    return {"cap": cap, "threads": threads, "posts_each": posts, "rounds": rounds, "most_unfinished": worst}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="how long to post tiny jobs")
    parser.add_argument("--bodies", type=int, default=12, help="how many ~15.7 MB bodies to post")
    parser.add_argument("--cap", type=int, default=20, help="max_queued_jobs in the race")
    parser.add_argument("--threads", type=int, default=16, help="clients racing for the cap")
    args = parser.parse_args()
    report = {
        "tiny_jobs": tiny_jobs(args.seconds),
        "big_bodies": big_bodies(args.bodies),
        "cap_race": cap_race(args.cap, args.threads, 3),
    }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
