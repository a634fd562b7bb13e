"""A plan request's time while robot films hold the jobs' workers, against the same request on an idle server.

Issue 30 item 3: three ``POST /v1/simulations`` with ``robot: true, video: "mp4"`` once held
both planner workers and a one-step plan waited for them. Here the films are jobs in the jobs'
own workers; the ratio of the plan's median time under films to its median on the idle server
says whether interactive capacity is separate (target: at most 3x; the machine is shared, and
the films take CPU).

    PYTHONPATH=$PWD python benchmarks/interactive.py [--rounds 7]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

import yaml
from fastapi.testclient import TestClient

from causalplan.service.main import create_app
from causalplan.settings import Settings

DESK_LAMP: dict[str, Any] = yaml.safe_load((Path(__file__).parents[1] / "examples/paper/desk_lamp.yaml").read_text())
TARGET = 3.0


def _new_model() -> dict[str, Any]:
    """The desk lamp with its intermediate effect renamed: a request no cache has seen."""
    effect = f"electricity flows {uuid.uuid4().hex[:8]}"
    return {**DESK_LAMP, "rules": [rule.replace("electricity flows", effect) for rule in DESK_LAMP["rules"]]}


def _plan_seconds(client: TestClient, rounds: int) -> list[float]:
    times = []
    for _ in range(rounds):
        started = time.perf_counter()
        response = client.post("/v1/plans", json={"model": _new_model()})
        times.append(time.perf_counter() - started)
        assert response.status_code == 200 and response.json()["status"] == "solved", response.text
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        settings = Settings(
            database_url=f"sqlite:///{Path(folder) / 'bench.db'}",
            planning_workers=2,
            job_poll_seconds=0.05,
            draw_plans_ahead=False,
        )
        with TestClient(create_app(settings)) as client:
            _plan_seconds(client, 2)  # warm the workers
            idle = _plan_seconds(client, args.rounds)
            films = []
            for _ in range(3):
                response = client.post("/v1/simulations", json={"model": DESK_LAMP, "robot": True, "video": "mp4"})
                assert response.status_code == 202, response.text
                films.append(response.json()["url"])
            while client.get(films[0]).json()["status"] != "running":
                time.sleep(0.05)
            loaded = _plan_seconds(client, args.rounds)
            still = client.get(films[0]).json()["status"]
            for url in films:
                client.delete(url)
    ratio = statistics.median(loaded) / statistics.median(idle)
    print(f"plan request, idle server: median {statistics.median(idle) * 1000:.1f} ms ({args.rounds} rounds)")
    print(f"plan request, 3 robot films queued: median {statistics.median(loaded) * 1000:.1f} ms (film: {still})")
    print(f"ratio {ratio:.2f}x (target <= {TARGET:g}x): {'met' if ratio <= TARGET else 'NOT met'}")


if __name__ == "__main__":
    main()
