"""Checks of a running compose stack (docker/compose.yaml), end to end, through nginx.

    python docker/compose_smoke.py [--engine podman|docker] [--url http://127.0.0.1:8000]

docker/compose-smoke.sh brings the stack up, runs this, and tears it down. What it checks, in
order, each printed as it passes:

1. /health through nginx says ok; every replica passes its image's health check, and nginx
   reaches each of them;
2. the replicas migrated the database once: one schema revision, neither replica restarted;
3. a participant's steps (the demo: tutorial, steps 1-3) reach both replicas, and the study
   goes on whichever replica answers;
4. X-Forwarded-For is believed only from nginx: a forged address sent through nginx, or sent
   straight to a replica from another container, is not taken as the client's;
5. a batch job posted through nginx (``POST /v1/jobs``, kind ``batch``) is judged on the Dask
   workers;
6. with one replica killed, the service still answers through nginx (health, a plan).

Containers are found by compose's labels (the same under Docker Compose and podman-compose), and
looked into with the engine's own commands (``logs``, ``exec``, ``inspect``, ``kill``): which
replica answered a request is read from the replicas' access logs (on by default). Exits
non-zero, saying what was wrong, at the first check that fails. Needs only httpx and PyYAML
(dependencies of the project).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import httpx
import yaml

PROJECT = "causalplan"
EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
BATCH_TRIALS = EXAMPLES / "batch" / "trials.jsonl"
DESK_LAMP = EXAMPLES / "paper" / "desk_lamp.yaml"
WAIT_SECONDS = 180.0
JOB_SECONDS = 300.0
NGINX_FAIL_TIMEOUT_SECONDS = 10  # nginx's default: how long it sets aside a replica that failed
KILLED_REQUEST_SECONDS = 30.0  # a request must not wait out nginx's default connect timeout (60 s)
FORGED_THROUGH_NGINX = "203.0.113.9"  # documentation addresses (RFC 5737): no client has them
FORGED_FROM_INSIDE = "198.51.100.7"

# The demo participant's answers (as the web tests give them): the desk lamp, then the flashlight.
TUTORIAL = {
    "answer:sticker": "no",
    "answer:diffuse": "no",
    "answer:and": "and",
    "rules": "store energy AND turn the axle CAUSES the axle spins\n"
    "the axle spins AND roll on the ground CAUSES motion",
}
LAMP_FUNCTIONS = {
    "part:base_with_cables": "provide electricity",
    "part:light_bulb": "turn electricity into light\nclose the circuit",
}
LAMP_RULES = {
    "rules": "provide electricity AND close the circuit CAUSES electricity flows\n"
    "electricity flows AND turn electricity into light CAUSES light"
}
FLASHLIGHT_CHOICES = {
    "chosen:batteries": "provide electricity",
    "chosen:head": ["turn electricity into light", "close the circuit"],
}


STARTED = time.monotonic()


def report(line: str) -> None:
    """Print a passed check, with the seconds since the checks began (CI's log shows where time goes)."""
    print(f"[{time.monotonic() - STARTED:4.0f} s] {line}", flush=True)


class SmokeError(Exception):
    """A check of the stack failed; the message says which and what was seen."""


def check(condition: bool, message: str) -> None:
    if not condition:
        raise SmokeError(message)


class Engine:
    """The container engine's command line (podman or docker), for this compose project."""

    def __init__(self, command: str) -> None:
        self.command = command

    def run(self, *arguments: str, check: bool = True, stdin: str | None = None) -> str:
        completed = subprocess.run(
            [self.command, *arguments], input=stdin, capture_output=True, text=True, check=False, timeout=120
        )
        if check and completed.returncode != 0:
            raise SmokeError(f"`{self.command} {' '.join(arguments)}` failed: {completed.stderr.strip()}")
        return completed.stdout

    def logs(self, container: str) -> str:
        """Return what a container printed (its standard output and error)."""
        completed = subprocess.run([self.command, "logs", container], capture_output=True, text=True, timeout=120)
        return completed.stdout + completed.stderr

    def containers(self, service: str) -> list[str]:
        """Return the names of the running containers of one compose service, sorted."""
        output = self.run(
            "ps",
            "--filter",
            f"label=com.docker.compose.project={PROJECT}",
            "--filter",
            f"label=com.docker.compose.service={service}",
            "--format",
            "{{.Names}}",
        )
        return sorted(line.strip() for line in output.splitlines() if line.strip())

    def one(self, service: str) -> str:
        names = self.containers(service)
        check(len(names) == 1, f"expected one running '{service}' container, found {names}")
        return names[0]

    def inspect(self, container: str, template: str) -> str:
        return self.run("inspect", "--format", template, container).strip()

    def address(self, container: str) -> str:
        return self.inspect(container, "{{range .NetworkSettings.Networks}}{{.IPAddress}}{{end}}")

    def is_healthy(self, container: str) -> bool:
        """Return whether the container passes its health check (podman: run it now; docker: its last state)."""
        if self.command.endswith("podman"):
            # Without systemd podman schedules no health checks: run the image's check once.
            return subprocess.run([self.command, "healthcheck", "run", container], capture_output=True).returncode == 0
        return self.inspect(container, "{{.State.Health.Status}}") == "healthy"

    def sql(self, query: str) -> list[str]:
        """Return the rows of a query on the stack's database (psql in the postgres container)."""
        output = self.run(
            "exec",
            self.one("postgres"),
            "psql",
            "-U",
            PROJECT,
            "-d",
            PROJECT,
            "-At",
            "-v",
            "ON_ERROR_STOP=1",
            "-c",
            query,
        )
        return [line for line in output.splitlines() if line]

    def python_in(self, container: str, code: str) -> str:
        """Return what a Python program printed, run in a container of the service image."""
        return self.run("exec", "-i", container, "python", "-", stdin=code)


def wait_healthy(client: httpx.Client) -> dict[str, Any]:
    """Return /health through nginx once it says ok (the replicas probe their planners at start)."""
    deadline = time.monotonic() + WAIT_SECONDS
    last = "no answer"
    while time.monotonic() < deadline:
        try:
            answer = client.get("/health")
            if answer.status_code == 200 and answer.json()["status"] == "ok":
                health: dict[str, Any] = answer.json()
                return health
            last = f"{answer.status_code} {answer.text[:200]}"
        except httpx.TransportError as exc:
            last = repr(exc)
        time.sleep(1)
    raise SmokeError(f"/health through nginx did not say ok within {WAIT_SECONDS:g} s; last: {last}")


def forwarded_health(log: str, nginx: str) -> bool:
    """Return whether a replica's access log shows a /health that nginx (``ADDRESS:``) passed on."""
    return any(nginx in line and '"GET /health HTTP/1.1" 200' in line for line in log.splitlines())


def check_health(engine: Engine, client: httpx.Client) -> list[str]:
    health = wait_healthy(client)
    replicas = engine.containers("service")
    check(len(replicas) >= 2, f"expected at least two replicas of 'service', found {replicas}")
    deadline = time.monotonic() + WAIT_SECONDS
    unhealthy = replicas
    while unhealthy and time.monotonic() < deadline:
        unhealthy = [name for name in unhealthy if not engine.is_healthy(name)]
        if unhealthy:
            time.sleep(2)
    check(not unhealthy, f"replicas failing their health check: {unhealthy}")
    for service in ("postgres", "dask-scheduler"):
        check(engine.is_healthy(engine.one(service)), f"'{service}' fails its health check")
    report(f"health: ok through nginx (causalplan {health['version']}); replicas {', '.join(replicas)} healthy")
    # nginx sets aside a replica that refused a connection while it started (for fail_timeout,
    # 10 s): ask until /health through nginx has reached each replica, as their logs show.
    nginx = f"{engine.address(engine.one('nginx'))}:"
    deadline = time.monotonic() + WAIT_SECONDS
    unreached = replicas
    while unreached and time.monotonic() < deadline:
        check(client.get("/health").status_code == 200, "/health through nginx stopped answering 200")
        unreached = [name for name in unreached if not forwarded_health(engine.logs(name), nginx)]
        if unreached:
            time.sleep(1)
    check(not unreached, f"/health through nginx never reached {unreached}")
    report(f"nginx: /health through it reached each of {', '.join(replicas)}")
    revision = health["database"]["expected_revision"]
    stored = engine.sql("SELECT version_num FROM alembic_version")
    check(stored == [revision], f"alembic_version holds {stored}, expected [{revision!r}]")
    for name in replicas:
        restarts = engine.inspect(name, "{{.RestartCount}}")
        check(restarts == "0", f"{name} restarted {restarts} time(s):\n{engine.logs(name)[-2000:]}")
        check("Traceback" not in engine.logs(name), f"{name} logged a traceback:\n{engine.logs(name)}")
    report(f"migrations: the schema is at {revision}, made once; no replica restarted or logged a traceback")
    return replicas


def post_form(client: httpx.Client, path: str, form: dict[str, Any]) -> None:
    answer = client.post(path, data=form, follow_redirects=False)
    check(answer.status_code == 303, f"POST {path}: expected 303, got {answer.status_code}: {answer.text[:500]}")


def check_participant(engine: Engine, client: httpx.Client, replicas: list[str]) -> str:
    """Take a demo participant through the study; return its code."""
    started = client.post("/try", headers={"X-Forwarded-For": FORGED_THROUGH_NGINX}, follow_redirects=False)
    check(started.status_code == 303, f"POST /try: expected 303, got {started.status_code}: {started.text[:500]}")
    code = str(started.headers["location"]).removeprefix("/p/")
    post_form(client, f"/p/{code}/tutorial", TUTORIAL)
    post_form(client, f"/p/{code}/step1/1", LAMP_FUNCTIONS)
    post_form(client, f"/p/{code}/step2", LAMP_RULES)
    post_form(client, f"/p/{code}/step3/1", FLASHLIGHT_CHOICES)
    verdict = client.get(f"/p/{code}/step3/1")
    check(verdict.status_code == 200, f"the verdict page: {verdict.status_code}")
    post_form(client, f"/p/{code}/step3/1/next", {})
    finished = engine.sql(f"SELECT finished_at IS NOT NULL FROM participants WHERE code = '{code}'")
    check(finished == ["t"], f"participant {code} is not recorded as finished: {finished}")
    served = {name: engine.logs(name).count(f"/p/{code}") for name in replicas}
    check(
        sum(1 for count in served.values() if count) >= 2,
        f"the participant's requests did not reach two replicas: {served}",
    )
    report(
        f"participant: {code} finished the study; its requests per replica: "
        + ", ".join(f"{name} {count}" for name, count in served.items())
    )
    return code


def check_forwarded_for(engine: Engine, replicas: list[str]) -> None:
    nginx_address = engine.address(engine.one("nginx"))
    # The demo's start limit counts per client and minute (window_counts): the client it saw.
    # Read at once: a window that has ended is deleted at the next start.
    through_nginx = engine.sql("SELECT DISTINCT client FROM window_counts")
    check(through_nginx != [], "the demo start through nginx recorded no client")
    check(FORGED_THROUGH_NGINX not in through_nginx, f"a forged X-Forwarded-For was believed: {through_nginx}")
    check(nginx_address not in through_nginx, f"nginx's own address was taken as the client's: {through_nginx}")
    # Straight to a replica from another container of the network: not a trusted proxy.
    insider = engine.one("dask-worker")
    insider_address = engine.address(insider)
    # The service image has no httpx; urllib follows the 303, so the status is the first page's.
    status = engine.python_in(
        insider,
        "import urllib.request\n"
        f"request = urllib.request.Request('http://{engine.address(replicas[0])}:8000/try', data=b'', "
        f"headers={{'X-Forwarded-For': '{FORGED_FROM_INSIDE}'}})\n"
        "print(urllib.request.urlopen(request, timeout=60).status)\n",
    ).strip()
    check(status == "200", f"POST /try straight to a replica: {status}")
    seen = engine.sql("SELECT DISTINCT client FROM window_counts")
    check(FORGED_FROM_INSIDE not in seen, f"X-Forwarded-For was believed from {insider_address}, not nginx: {seen}")
    check(insider_address in seen, f"the direct client {insider_address} was not recorded: {seen}")
    report(
        f"X-Forwarded-For: through nginx ({nginx_address}) the client is {', '.join(through_nginx)}, not the forged "
        f"{FORGED_THROUGH_NGINX}; straight from {insider_address} the header is ignored"
    )


DASK_PROBE = """
import json
from distributed import Client
with Client("tcp://127.0.0.1:8786", timeout=30) as client:
    executed = client.run(lambda dask_worker: dask_worker.state.executed_count)
    prefixes = client.run_on_scheduler(lambda dask_scheduler: sorted(dask_scheduler.task_prefixes))
print(json.dumps({"executed": executed, "prefixes": prefixes}))
"""


def dask_counts(engine: Engine) -> dict[str, Any]:
    """Return each Dask worker's count of executed tasks, and the task names the scheduler has seen."""
    output = engine.python_in(engine.one("dask-scheduler"), DASK_PROBE)
    counts: dict[str, Any] = json.loads(output.strip().splitlines()[-1])
    return counts


def check_batch_on_dask(engine: Engine, client: httpx.Client) -> None:
    before = dask_counts(engine)
    check(len(before["executed"]) >= 1, f"the Dask scheduler has no workers: {before}")
    trials = BATCH_TRIALS.read_text(encoding="utf-8")
    posted = client.post("/v1/jobs", json={"kind": "batch", "trials": trials, "simulate": False})
    check(posted.status_code == 202, f"POST /v1/jobs: expected 202, got {posted.status_code}: {posted.text[:500]}")
    url = posted.json()["url"]
    deadline = time.monotonic() + JOB_SECONDS
    job = posted.json()
    while job["status"] in ("queued", "running") and time.monotonic() < deadline:
        time.sleep(1)
        job = client.get(url).json()
    check(job["status"] == "succeeded", f"the batch job ended {job['status']}: {job.get('error')}")
    expected = len(trials.splitlines())
    check(job["result"]["trials"] == expected, f"the batch judged {job['result']['trials']} of {expected} trials")
    after = dask_counts(engine)
    executed = sum(after["executed"].values()) - sum(before["executed"].values())
    check(executed >= 1, f"the Dask workers executed no task for the job: before {before}, after {after}")
    check("judge_chunk" in after["prefixes"], f"the scheduler saw no judge_chunk task: {after['prefixes']}")
    report(
        f"batch job: {expected} trials {job['result']['verdicts']} judged on the Dask cluster "
        f"({executed} task(s) on {len(after['executed'])} worker process(es))"
    )


def check_replica_killed(engine: Engine, client: httpx.Client, replicas: list[str]) -> None:
    model = yaml.safe_load(DESK_LAMP.read_text(encoding="utf-8"))
    victim = replicas[0]
    engine.run("kill", victim)
    answers: list[int] = []
    # Past nginx's fail_timeout, so that nginx tries the dead replica again at least once: the
    # request it tries it with must still be answered, by another replica, without hanging.
    until = time.monotonic() + NGINX_FAIL_TIMEOUT_SECONDS + 5
    while time.monotonic() < until or len(answers) < 2 * len(replicas):
        health = client.get("/health", timeout=KILLED_REQUEST_SECONDS)
        answers.append(health.status_code)
        plan = client.post("/v1/plans", json={"model": model}, timeout=KILLED_REQUEST_SECONDS)
        check(
            plan.status_code == 200 and plan.json()["status"] == "solved", f"a plan after the kill: {plan.text[:500]}"
        )
        answers.append(plan.status_code)
        time.sleep(0.5)
    check(all(status == 200 for status in answers), f"answers after the kill: {answers}")
    survivors = [name for name in engine.containers("service") if name != victim]
    report(f"replica killed: {victim}; nginx answered all {len(answers)} requests after it (on {', '.join(survivors)})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--engine", default="podman", help="the container engine's command: podman or docker")
    parser.add_argument("--url", default="http://127.0.0.1:8000", help="nginx as compose publishes it")
    arguments = parser.parse_args()
    engine = Engine(arguments.engine)
    try:
        with httpx.Client(base_url=arguments.url, timeout=120) as client:
            replicas = check_health(engine, client)
            check_participant(engine, client, replicas)
            check_forwarded_for(engine, replicas)
            check_batch_on_dask(engine, client)
            check_replica_killed(engine, client, replicas)
    except SmokeError as exc:
        sys.exit(f"compose smoke: FAILED: {exc}")
    except httpx.HTTPError as exc:  # e.g. nginx not answering in time
        sys.exit(f"compose smoke: FAILED: {exc.request.method} {exc.request.url}: {exc!r}")
    print("compose smoke: all checks passed")


if __name__ == "__main__":
    main()
