"""Time POST /v1/plans on a real server (1 and 8 concurrent clients) against the in-process solve.

    python benchmarks/service.py [--requests N] [--workers W] [--planner fd] [--quick]

Starts ``causalplan serve`` on a free loopback port (a temporary SQLite database), then sends
bounded loops of requests over kept-alive connections of the standard library's http.client
(the lightest client here; one row per kind repeats it with httpx, which adds its own cost
per request). Requests go to the paper's four objects in turn (PAPER_CASES: the desk-lamp
model on the desk lamp and, through its step-3 mapping, on the flashlight; the candle model on
the candle and on the kerosene lamp). Each "new" request is a model the server has not seen
(its intermediate effect renamed), so it is read, planned and stored; "cached" requests repeat
the four models (still stored each time). The reference is ``plan_task`` on the same four tasks
in turn, in a freshly spawned process as the CLI runs it, measured in the same run; so is the
same solve through unified-planning's OneshotPlanner. Ratios are service / in-process; "beside
solve" is what a planned request cost beyond the solve the answer reports (HTTP, reading,
storing, the hop to a worker). The last lines check issue 8's targets. Results also go to
``benchmarks/results/service.json``. See benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import http.client
import json
import multiprocessing
import os
import platform
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.parse
import uuid
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from dataclasses import asdict, dataclass, field
from datetime import UTC, datetime
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import httpx
import yaml

if TYPE_CHECKING:
    from causalplan.pddl.task import PlanningTask

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "service.json"
EXAMPLES = ROOT / "examples"
PAPER_CASES: tuple[tuple[str, str, str | None, str], ...] = (
    ("desk lamp", "paper/desk_lamp.yaml", None, "electricity flows"),
    ("flashlight", "paper/desk_lamp.yaml", "paper/flashlight_mapping.yaml", "electricity flows"),
    ("candle", "near/candle.yaml", None, "fuel at the tip"),
    ("kerosene lamp", "near/candle.yaml", "near/kerosene_lamp_mapping.yaml", "fuel at the tip"),
)
"""The paper's four objects, planned in turn: (object, model, step-3 mapping or None, an intermediate effect)."""
CLIENT_COUNTS = (1, 8)
START_SECONDS = 60.0
MAX_SECONDS_PER_SCENARIO = 120.0
UP_REQUESTS = 60
"""Solves through unified-planning (~0.2 s each): enough for its p50, which is ~15x the service's."""


@dataclass
class Scenario:
    """The latencies of one scenario, and what came back."""

    name: str
    clients: int
    seconds: list[float]
    wall: float
    statuses: dict[str, int]
    outside_solve: list[float] = field(default_factory=list)
    """Per planned request: its latency less the solve's own time (the answer's timing.total)."""

    @property
    def p50(self) -> float:
        return statistics.median(self.seconds)

    @property
    def p95(self) -> float:
        ordered = sorted(self.seconds)
        return ordered[min(len(ordered) - 1, round(0.95 * (len(ordered) - 1)))]

    @property
    def throughput(self) -> float:
        return len(self.seconds) / self.wall


@cache
def _document(relative: str) -> dict[str, Any]:
    """Return an example's document, read once (callers must not change it)."""
    document: dict[str, Any] = yaml.safe_load((EXAMPLES / relative).read_text())
    return document


def paper_body(index: int) -> dict[str, Any]:
    """Return the request body of paper case ``index % 4``, its intermediate effect renamed.

    Renamed: a model the server has not seen (the canonical planning problem is still the case's own).
    """
    _, model_path, mapping_path, effect = PAPER_CASES[index % len(PAPER_CASES)]
    model = _document(model_path)
    new_effect = f"{effect} {uuid.uuid4().hex[:10]}"
    renamed = {**model, "rules": [rule.replace(effect, new_effect) for rule in model["rules"]]}
    return {"model": renamed} | ({"mapping": _document(mapping_path)} if mapping_path else {})


def paper_tasks() -> list[PlanningTask]:
    """Return the planning tasks of PAPER_CASES, in their order."""
    from causalplan.inputs import load_mapping, load_model
    from causalplan.objects.catalog import load_catalog
    from causalplan.pddl.task import build_task

    catalog = load_catalog()
    tasks = []
    for _, model_path, mapping_path, _ in PAPER_CASES:
        model = load_model(EXAMPLES / model_path, catalog).model
        mapping = load_mapping(EXAMPLES / mapping_path, catalog).mapping if mapping_path else None
        assert model is not None and (mapping_path is None or mapping is not None)
        tasks.append(build_task(model, catalog.get((mapping or model.labelling).object_id), mapping))
    return tasks


def in_process_latencies(requests: int, planner: str) -> tuple[list[float], float]:
    """Solve the desk-lamp task ``requests`` times with ``plan_task`` (after a warm-up); return times and wall."""
    from causalplan import caches
    from causalplan.planners.pipeline import plan_task

    tasks = paper_tasks()
    assert all(plan_task(task, planner).has_plan for task in tasks)  # warm-up
    seconds = []
    started = time.perf_counter()
    for index in range(requests):
        caches.current().fd_answers.clear()  # every solve a real one, as for a model never seen
        solve_started = time.perf_counter()
        result = plan_task(tasks[index % len(tasks)], planner)
        seconds.append(time.perf_counter() - solve_started)
        assert result.has_plan, result.message
    return seconds, time.perf_counter() - started


def up_latencies(requests: int) -> tuple[list[float], float]:
    """Solve the same tasks through unified-planning's OneshotPlanner("fast-downward"); return times and wall."""
    from causalplan.planners.up_problem import solve_with_up

    tasks = paper_tasks()
    for task in tasks:  # warm-up: imports
        solve_with_up(task, "fast-downward")
    seconds = []
    started = time.perf_counter()
    for index in range(requests):
        solve_started = time.perf_counter()
        outcome = solve_with_up(tasks[index % len(tasks)], "fast-downward")
        seconds.append(time.perf_counter() - solve_started)
        assert outcome.actions, outcome.message
    return seconds, time.perf_counter() - started


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


def start_server(folder: Path, workers: int, cold: bool = False) -> tuple[subprocess.Popen[bytes], str]:
    """Start ``causalplan serve`` on loopback; return it and its base URL once /health answers.

    ``cold``: the workers keep no Fast Downward answers, so every new model is really solved
    (otherwise a model that differs only in its words shares the solve of an earlier one).
    """
    port = free_port()
    environment = {**os.environ, "CAUSALPLAN_QUEUE_SIZE": "64", "CAUSALPLAN_CACHE_SIZE": "4096"}
    if cold:
        environment["CAUSALPLAN_SOLVE_CACHE_SIZE"] = "0"
    command = [sys.executable, "-m", "causalplan.cli", "serve", "--host", "127.0.0.1", "--port", str(port)]
    command += ["--workers", str(workers), "--database-url", f"sqlite:///{folder / 'bench.sqlite3'}"]
    # Its log (one access line per request) goes to a file: an unread pipe would fill and stall it.
    log = folder / "server.log"
    with log.open("wb") as handle:
        server = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=handle, env=environment)
    base = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + START_SECONDS
    while time.monotonic() < deadline:
        if server.poll() is not None:
            sys.exit(f"the server stopped: {log.read_text(errors='replace')}")
        try:
            if httpx.get(f"{base}/health", timeout=30).status_code == 200:
                return server, base
        except httpx.TransportError:
            time.sleep(0.1)
    server.kill()
    sys.exit(f"the server did not answer within {START_SECONDS:g} s")


class KeepAliveClient:
    """POST JSON over one kept-alive HTTP/1.1 connection (the standard library's http.client).

    The latencies are the service's: this client costs less per request than httpx (its own
    scenario row shows the difference in the same run).
    """

    def __init__(self, base: str) -> None:
        url = urllib.parse.urlsplit(base)
        self.connection = http.client.HTTPConnection(url.hostname or "127.0.0.1", url.port, timeout=120)

    def __call__(self, path: str, body: dict[str, Any]) -> tuple[int, dict[str, Any]]:
        self.connection.request("POST", path, json.dumps(body), {"Content-Type": "application/json"})
        response = self.connection.getresponse()
        data: dict[str, Any] = json.loads(response.read())
        return response.status, data

    def __enter__(self) -> KeepAliveClient:
        return self

    def __exit__(self, *_: object) -> None:
        self.connection.close()


class HttpxClient:
    """POST JSON with httpx (one client, its connection kept alive): what many Python callers use."""

    def __init__(self, base: str) -> None:
        self.client = httpx.Client(base_url=base, timeout=120)

    def __call__(self, path: str, body: dict[str, Any]) -> tuple[int, dict[str, Any]]:
        response = self.client.post(path, json=body)
        data: dict[str, Any] = response.json()
        return response.status_code, data

    def __enter__(self) -> HttpxClient:
        return self

    def __exit__(self, *_: object) -> None:
        self.client.close()


def run_clients(
    base: str, name: str, clients: int, requests: int, planner: str, cached: bool, client: str = "http.client"
) -> Scenario:
    """Send ``requests`` POST /v1/plans from ``clients`` threads (each its own connection).

    ``client``: "http.client" (the standard library's, the lightest here) or "httpx".
    """
    fixed = [paper_body(index) for index in range(len(PAPER_CASES))]
    lock = threading.Lock()
    seconds: list[float] = []
    outside_solve: list[float] = []
    statuses: dict[str, int] = {}
    deadline = time.monotonic() + MAX_SECONDS_PER_SCENARIO

    def client_loop(count: int) -> None:
        post = HttpxClient(base) if client == "httpx" else KeepAliveClient(base)
        with post:
            for index in range(count):
                if time.monotonic() > deadline:
                    return
                body = {**(fixed[index % len(fixed)] if cached else paper_body(index)), "planner": planner}
                started = time.perf_counter()
                status, data = post("/v1/plans", body)
                elapsed = time.perf_counter() - started
                outcome = data.get("status") if status == 200 else f"http {status}"
                solve = data.get("timing", {}).get("total") if status == 200 else None
                with lock:
                    seconds.append(elapsed)
                    statuses[str(outcome)] = statuses.get(str(outcome), 0) + 1
                    if not data.get("cached", True) and isinstance(solve, float):  # a cached answer's timing is old
                        outside_solve.append(elapsed - solve)

    if cached:  # the first answers fill the cache
        for body in fixed:
            httpx.post(f"{base}/v1/plans", json={**body, "planner": planner}, timeout=120).raise_for_status()
    shares = [requests // clients + (1 if index < requests % clients else 0) for index in range(clients)]
    started = time.perf_counter()
    with ThreadPoolExecutor(clients) as pool:
        list(pool.map(client_loop, shares))
    return Scenario(name, clients, seconds, time.perf_counter() - started, statuses, outside_solve)


def milliseconds(value: float) -> str:
    return f"{value * 1000:.1f} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--requests",
        type=int,
        default=200,
        help="requests per scenario (default 200: a p50 over a few seconds, not one slow moment of a shared "
        "machine); the unified-planning reference sends at most UP_REQUESTS",
    )
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 2, help="planner workers (default: cores)")
    parser.add_argument("--planner", default="fd", help="planner on both sides (default fd)")
    parser.add_argument("--quick", action="store_true", help="smoke run: 16 requests per scenario")
    args = parser.parse_args()
    requests = 16 if args.quick else max(8, args.requests)

    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as reference_process:
        reference_seconds, reference_wall = reference_process.submit(
            in_process_latencies, requests, args.planner
        ).result()
    reference = Scenario("in-process plan_task", 1, reference_seconds, reference_wall, {"solved": requests})

    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as up_process:
        up_seconds, up_wall = up_process.submit(up_latencies, min(requests, UP_REQUESTS)).result()
    up_reference = Scenario("unified-planning OneshotPlanner", 1, up_seconds, up_wall, {"solved": len(up_seconds)})

    scenarios: list[Scenario] = []
    for cold in (True, False):
        with tempfile.TemporaryDirectory(prefix="causalplan-bench-") as folder:
            server, base = start_server(Path(folder), args.workers, cold)
            try:
                for index in range(2 * args.workers * len(PAPER_CASES)):  # warm-up: every worker, every case
                    body = {**paper_body(index), "planner": args.planner}
                    httpx.post(f"{base}/v1/plans", json=body, timeout=120).raise_for_status()
                for cached in (False, True) if not cold else (False,):
                    for clients in CLIENT_COUNTS:
                        name = "POST /v1/plans, " + (
                            "cached" if cached else "new model, cold" if cold else "new words, same problem"
                        )
                        scenarios.append(run_clients(base, name, clients, requests, args.planner, cached))
                    client = "httpx"
                    name = "POST /v1/plans, " + ("cached" if cached else "new model, cold") + ", httpx client"
                    if cold or cached:
                        scenarios.append(run_clients(base, name, 1, requests, args.planner, cached, client))
            finally:
                server.send_signal(signal.SIGINT)
                server.wait(30)

    header = (
        f"{'scenario':<52} {'clients':>7} {'requests':>8} {'p50':>10} {'p95':>10} {'beside solve':>12} {'req/s':>8} "
        f"{'p50 ratio':>9} {'req/s ratio':>11}  outcomes"
    )
    print(
        f"causalplan service benchmark: planner {args.planner}, {args.workers} worker(s), "
        f"{os.cpu_count()} core(s), Python {platform.python_version()}; requests rotate over the "
        f"{', '.join(case[0] for case in PAPER_CASES)}"
    )
    print(header)
    print("-" * len(header))
    for scenario in [reference, *scenarios, up_reference]:
        beside = milliseconds(statistics.median(scenario.outside_solve)) if scenario.outside_solve else "-"
        outcomes = ", ".join(f"{count} {status}" for status, count in sorted(scenario.statuses.items()))
        print(
            f"{scenario.name:<52} {scenario.clients:>7} {len(scenario.seconds):>8} {milliseconds(scenario.p50):>10} "
            f"{milliseconds(scenario.p95):>10} {beside:>12} {scenario.throughput:>8.1f} "
            f"{scenario.p50 / reference.p50:>8.2f}x {scenario.throughput / reference.throughput:>10.2f}x  {outcomes}"
        )
    print(
        "ratios: against the in-process plan_task (p50 latency: lower is better; req/s: higher is better); "
        "beside solve: median of (latency - the answer's timing.total), i.e. HTTP, reading, storing and the "
        "hop to a worker, for requests that were planned"
    )
    cold_one = next(s for s in scenarios if s.name.endswith("cold") and s.clients == 1)
    cached_one = next(s for s in scenarios if s.name.endswith("cached") and s.clients == 1)
    speedup = up_reference.p50 / cold_one.p50
    repeated = cached_one.p50 / cold_one.p50
    targets = [
        ("UP p50 / cold p50", f"{speedup:.1f}x", ">= 10x", speedup >= 10),
        ("cached p50 / cold p50", f"{repeated:.3f}", "<= 0.3", repeated <= 0.3),
    ]
    print("targets (ratios, this run):")
    for name, measured, target, is_met in targets:
        print(f"  {name:<22} {measured:>10}  target {target:<9} {'met' if is_met else 'NOT met'}")
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(
        json.dumps(
            {
                "when": datetime.now(UTC).isoformat(),
                "planner": args.planner,
                "workers": args.workers,
                "cores": os.cpu_count(),
                "scenarios": [
                    {**asdict(s), "p50_s": s.p50, "p95_s": s.p95, "requests_per_s": s.throughput}
                    for s in [reference, up_reference, *scenarios]
                ],
                "targets": [
                    {"target": name, "measured": measured, "goal": target, "met": is_met}
                    for name, measured, target, is_met in targets
                ],
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
