"""Fair shares under the round-four probe attacks (issue 40), repeated on one machine, in-process.

Four probes, each on a fresh SQLite database and an app run through Starlette's TestClient (no
socket is opened: every request stays in this process; the clients' addresses are the test
client's ``client=(address, port)``, documentation addresses):

1. repairs flood: one client sends ``POST /v1/transfers`` with ``"repair": true`` at
   ``time_limit`` 30 from ``--flood-threads`` threads for ``--seconds``, while another client
   plans (a new model each time, so every plan is solved); reports the other client's plan
   latency (p50, p95, max) against the same plans with nobody flooding, measured first in the
   same run, and the flooder's answers by code;
2. wrong tokens: ``--addresses`` addresses send wrong bearer tokens as fast as they can for
   ``--token-seconds`` while a valid API key reads its own job and the research token lists
   trials; reports their answers by code;
3. storage: one client without a key posts plans with ~15 KB inline models (stored, then 422) from
   4 threads for ``--growth-seconds``; reports the answers by code and the database's growth
   (file and write-ahead log, then the file after a checkpoint) against the client's allowance;
4. films: one address starts ``--participants`` demo participants (``POST /try``) and each asks
   for films of distinct fit lists; then a keyed client posts a one-trial batch; reports the
   films' answers by code, the batch's answer and the seconds until it finished.

Run: ``PYTHONPATH=. python benchmarks/fair_share.py`` (about 3-5 minutes; it stops by itself).
"""

from __future__ import annotations

import argparse
import collections
import itertools
import json
import sqlite3
import statistics
import tempfile
import threading
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import yaml
from fastapi.testclient import TestClient
from sqlalchemy.orm import Session

from causalplan.service.main import create_app
from causalplan.service.storage.allowance import stored_bytes
from causalplan.service.storage.records import utc_now
from causalplan.settings import Settings

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
API_KEY = "fair-share-benchmark-key-0001"
RESEARCH_TOKEN = "fair-share-benchmark-research"
KEY_AUTH = {"Authorization": f"Bearer {API_KEY}"}
RESEARCH_AUTH = {"Authorization": f"Bearer {RESEARCH_TOKEN}"}
FLOODER = "203.0.113.1"
OTHER = "198.51.100.2"
FAILED_MODEL: dict[str, Any] = {
    "object": "desk_lamp",
    "goal": "light",
    "functions": {
        "base_with_cables": ["provide electricity"],
        "light_bulb": ["turn electricity into light"],
        "shade": ["diffuse light"],
    },
    "rules": ["provide electricity AND turn electricity into light AND diffuse light CAUSES light"],
}
FAILED_MAPPING = {
    "object": "flashlight",
    "functions": {"batteries": ["provide electricity"], "case": ["hold things together"], "head": ["diffuse light"]},
}


def _settings(folder: Path, **overrides: Any) -> Settings:
    values: dict[str, Any] = {
        "database_url": f"sqlite:///{folder / 'probe.sqlite3'}",
        "data_folder": folder,
        "research_token": RESEARCH_TOKEN,
        "api_keys": [API_KEY],
        "draw_plans_ahead": False,
        "access_log": False,
        **overrides,
    }
    return Settings(**values)


@contextmanager
def _app(**overrides: Any) -> Iterator[TestClient]:
    with (
        tempfile.TemporaryDirectory(prefix="fair-share-") as name,
        TestClient(create_app(_settings(Path(name), **overrides)), raise_server_exceptions=False) as client,
    ):
        yield client


def _at(client: TestClient, address: str) -> TestClient:
    """Return a client of the running app whose requests come from ``address``."""
    return TestClient(client.app, client=(address, 40000), raise_server_exceptions=False)


def _code(response: Any) -> str:
    if response.status_code < 400:
        return str(response.status_code)
    try:
        return f"{response.status_code} {response.json()['error']['code']}"
    except (ValueError, KeyError):
        return str(response.status_code)


def _unique(model: dict[str, Any]) -> dict[str, Any]:
    """Return ``model`` with a new label in place of 'diffuse light' (a request no cache has seen)."""
    label = f"diffuse light {uuid.uuid4().hex[:8]}"
    text = json.dumps(model).replace("diffuse light", label)
    result: dict[str, Any] = json.loads(text)
    return result


def _percentile(values: list[float], share: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, round(share * len(ordered)) - 1))]


def _latencies(client: TestClient, count: int, pause: float) -> list[float]:
    desk_lamp = yaml.safe_load((EXAMPLES / "paper" / "desk_lamp.yaml").read_text())
    seconds = []
    for _ in range(count):
        began = time.perf_counter()
        answer = client.post("/v1/plans", json={"model": _unique(desk_lamp)})
        seconds.append(time.perf_counter() - began)
        if answer.status_code != 200:
            seconds[-1] = float("inf")  # a refusal is no answer: it counts as the worst
        time.sleep(pause)
    return seconds


def _summary(seconds: list[float]) -> dict[str, Any]:
    return {
        "plans": len(seconds),
        "refused": sum(1 for value in seconds if value == float("inf")),
        "p50_s": round(statistics.median(seconds), 3),
        "p95_s": round(_percentile(seconds, 0.95), 3),
        "max_s": round(max(seconds), 3),
    }


def repair_flood(seconds: float, flood_threads: int, plans: int) -> dict[str, Any]:
    """Another client's plans alone, then while one client floods repairs at time_limit 30."""
    with _app() as app:
        other, flooder = _at(app, OTHER), _at(app, FLOODER)
        _latencies(other, 3, 0.0)  # the workers warm
        alone = _latencies(other, plans, 0.2)
        answers: collections.Counter[str] = collections.Counter()
        stop = threading.Event()
        lock = threading.Lock()

        def flood() -> None:
            body = {"mapping": FAILED_MAPPING, "repair": True, "time_limit": 30}
            while not stop.is_set():
                answer = flooder.post("/v1/transfers", json={**body, "model": _unique(FAILED_MODEL)})
                with lock:
                    answers[_code(answer)] += 1
                if answer.status_code == 429:
                    stop.wait(min(float(answer.headers.get("retry-after", "1")), 1.0))

        threads = [threading.Thread(target=flood) for _ in range(flood_threads)]
        for thread in threads:
            thread.start()
        began = time.monotonic()
        time.sleep(2.0)  # the flood has taken what it can
        during: list[float] = []
        while time.monotonic() - began < seconds:
            during.extend(_latencies(other, 1, 0.3))
        stop.set()
        for thread in threads:
            thread.join(120)
    base, flooded = _summary(alone), _summary(during)
    return {
        "alone": base,
        "during_flood": flooded,
        "p95_ratio": round(flooded["p95_s"] / max(base["p95_s"], 1e-6), 2),
        "flooder_answers": dict(answers),
    }


def wrong_token_flood(seconds: float, addresses: int) -> dict[str, Any]:
    """Wrong tokens from many addresses while a valid key and the research token work."""
    with _app(planning_workers=1, job_runners=0) as app:
        keyed = _at(app, OTHER)
        job = keyed.post("/v1/jobs", json={"kind": "batch", "trials": "not a trial\n"}, headers=KEY_AUTH).json()
        guessers = [_at(app, f"203.0.113.{number}") for number in range(1, addresses + 1)]
        wrong: collections.Counter[str] = collections.Counter()
        right: collections.Counter[str] = collections.Counter()
        stop = threading.Event()
        lock = threading.Lock()

        def guess(client: TestClient) -> None:
            while not stop.is_set():
                answer = client.get(job["url"], headers={"Authorization": f"Bearer guess-{uuid.uuid4().hex}"})
                with lock:
                    wrong[_code(answer)] += 1

        threads = [threading.Thread(target=guess, args=(client,)) for client in guessers]
        for thread in threads:
            thread.start()
        began = time.monotonic()
        while time.monotonic() - began < seconds:
            for client in (keyed, guessers[0]):  # from a clean address and from a guessing one
                right["key " + _code(client.get(job["url"], headers=KEY_AUTH))] += 1
                right["research " + _code(client.get("/v1/trials", headers=RESEARCH_AUTH))] += 1
            time.sleep(0.1)
        stop.set()
        for thread in threads:
            thread.join(30)
    return {"addresses": addresses, "wrong_token_answers": dict(wrong), "right_token_answers": dict(right)}


def film_flood(participants: int, films_each: int, wait_seconds: float) -> dict[str, Any]:
    """One address's demo participants ask for films; then a keyed one-trial batch is posted and followed."""
    with _app(planning_workers=1, job_runners=1, job_poll_seconds=0.2, demo_starts_per_minute=0) as app:
        flooder = _at(app, FLOODER)
        films: collections.Counter[str] = collections.Counter()
        fits = itertools.cycle(
            [
                list(order)
                for size in (1, 2, 3)
                for order in itertools.product(["bulb_into_socket", "shade_onto_ring"], repeat=size)
            ]
        )
        for _ in range(participants):
            started = flooder.post("/try", follow_redirects=False)
            code = started.headers["location"].rstrip("/").split("/")[2]
            for _ in range(films_each):
                answer = flooder.post(f"/p/{code}/films", json={"object": "desk_lamp", "fits": next(fits)})
                films[_code(answer)] += 1
        lines = (EXAMPLES / "batch" / "trials.jsonl").read_text(encoding="utf-8").splitlines()[:1]
        began = time.monotonic()
        posted = _at(app, OTHER).post(
            "/v1/jobs", json={"kind": "batch", "trials": lines[0] + "\n", "simulate": False}, headers=KEY_AUTH
        )
        status, finished_after = None, None
        if posted.status_code == 202:
            while time.monotonic() - began < wait_seconds:
                status = app.get(posted.json()["url"], headers=KEY_AUTH).json()["status"]
                if status in ("succeeded", "failed"):
                    finished_after = round(time.monotonic() - began, 1)
                    break
                time.sleep(0.2)
        health = app.get("/health").json()["jobs"]
    return {
        "participants": participants,
        "film_answers": dict(films),
        "keyed_batch": _code(posted),
        "keyed_batch_status": status,
        "keyed_batch_finished_after_s": finished_after,
        "jobs_at_the_end": health,
    }


def _database_bytes(folder: Path) -> tuple[int, int]:
    """Return the bytes of the database file and of its write-ahead log (bounded by ``journal_size_limit``)."""
    main, log = folder / "probe.sqlite3", folder / "probe.sqlite3-wal"
    return main.stat().st_size, log.stat().st_size if log.exists() else 0


def _checkpoint(folder: Path) -> None:
    with sqlite3.connect(folder / "probe.sqlite3") as connection:
        connection.execute("PRAGMA wal_checkpoint(TRUNCATE)")


def _big_model(number: int) -> dict[str, Any]:
    """Return an invalid model of ~15 KB within the document limits: stored (as every inline model is), then a 422.

    Its row holds the reader's report of 150 bad rules too: about 95 KB counted a row (39.9 MB in
    418 rows in RESULTS.md's 2026-12-05 run).
    """
    labels = [f"function {number} {index} " + "x" * 60 for index in range(150)]
    return {"object": "desk_lamp", "functions": {}, "rules": [f"{label} CAUSES light" for label in labels]}


def storage_growth(seconds: float, threads: int) -> dict[str, Any]:
    """One client without a key posts plans with big inline models from ``threads`` threads for ``seconds``."""
    with tempfile.TemporaryDirectory(prefix="fair-share-") as name:
        folder = Path(name)
        settings = _settings(folder, planning_workers=1, job_runners=0)
        with TestClient(create_app(settings), raise_server_exceptions=False) as app:
            client = _at(app, FLOODER)
            before, _ = _database_bytes(folder)
            answers: collections.Counter[str] = collections.Counter()
            lock = threading.Lock()
            numbers = itertools.count()
            began = time.monotonic()

            def post() -> None:
                while time.monotonic() - began < seconds:
                    answer = client.post("/v1/plans", json={"model": _big_model(next(numbers))})
                    with lock:
                        answers[_code(answer)] += 1

            workers = [threading.Thread(target=post) for _ in range(threads)]
            for worker in workers:
                worker.start()
            for worker in workers:
                worker.join()
            file_then, log_then = _database_bytes(folder)
            _checkpoint(folder)  # the log's pages are in the file now: the file holds everything
            file_after, _ = _database_bytes(folder)
            with Session(app.app.state.services.engine) as session:  # type: ignore[attr-defined]
                stored = stored_bytes(session, f"address:{FLOODER}", utc_now())
    return {
        "seconds": seconds,
        "threads": threads,
        "answers": dict(answers),
        "allowance_mb": settings.anonymous_job_megabytes,
        "rows_stored_mb": round(stored / 1e6, 1),
        "file_and_log_grew_mb": round((file_then + log_then - before) / 1e6, 1),
        "file_grew_mb_after_checkpoint": round((file_after - before) / 1e6, 1),
    }


PROBES = ("repair_flood", "wrong_tokens", "storage", "films")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="how long the repairs flood lasts")
    parser.add_argument("--flood-threads", type=int, default=8, help="threads of the flooding client")
    parser.add_argument("--plans", type=int, default=20, help="the other client's plans with nobody flooding")
    parser.add_argument("--token-seconds", type=float, default=20.0, help="how long wrong tokens are sent")
    parser.add_argument("--addresses", type=int, default=10, help="addresses sending wrong tokens")
    parser.add_argument("--participants", type=int, default=10, help="demo participants of the film flood")
    parser.add_argument("--films", type=int, default=10, help="films each participant asks for")
    parser.add_argument("--wait", type=float, default=300.0, help="longest wait for the keyed batch")
    parser.add_argument("--growth-seconds", type=float, default=60.0, help="how long big models are posted")
    parser.add_argument(
        "--probes", default=",".join(PROBES), help=f"which probes, comma-separated (default: {','.join(PROBES)})"
    )
    args = parser.parse_args()
    probes = {
        "repair_flood": lambda: repair_flood(args.seconds, args.flood_threads, args.plans),
        "wrong_tokens": lambda: wrong_token_flood(args.token_seconds, args.addresses),
        "storage": lambda: storage_growth(args.growth_seconds, 4),
        "films": lambda: film_flood(args.participants, args.films, args.wait),
    }
    report = {name: probes[name]() for name in args.probes.split(",")}
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
