"""The launch benchmark at a small scale: 60 participants, two replicas on PostgreSQL, one killed midway.

It runs as its own process (Locust patches the standard library with gevent when imported).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RUN_SECONDS = 1200
"""A bound on the whole run (start-up, 60 arrivals over 30 s, their journeys); it ends by itself well before."""


@pytest.mark.slow
def test_sixty_participants_lose_no_save_and_see_no_5xx_when_a_replica_dies(tmp_path: Path) -> None:
    report_path = tmp_path / "launch.json"
    command = [
        sys.executable,
        str(ROOT / "benchmarks" / "launch.py"),
        "--participants",
        "60",
        "--arrival-seconds",
        "30",
        "--think",
        "0.2-1",
        "--no-draw-ahead",
        "--out",
        str(report_path),
    ]
    finished = subprocess.run(command, capture_output=True, text=True, timeout=RUN_SECONDS, cwd=ROOT)
    assert report_path.exists(), finished.stdout + finished.stderr
    report = json.loads(report_path.read_text())
    assert finished.returncode == 0, finished.stdout + finished.stderr
    assert report["acknowledged_saves_missing"] == 0 and report["acknowledged_saves"] > 60
    assert report["server_errors_live_replica"] == 0
    assert report["killed_replica_at_seconds"] is not None and report["answers_per_replica"][0] > 0
    allowed = report["completions_allowed_per_condition"]
    assert sum(report["completions"].values()) > 0
    assert all(report["completions"].get(name, 0) <= most for name, most in allowed.items())
    assert report["page_seconds"]["p95"] is not None
