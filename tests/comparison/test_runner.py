"""``causalplan compare``: one process per run, a failing planner is a row, files are written."""

from __future__ import annotations

import csv
import json
import os
import signal
import threading
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.comparison import tasks
from causalplan.comparison.runner import compare, run_once
from causalplan.errors import CausalPlanError
from tests.conftest import EXAMPLES, ROOT


@pytest.mark.slow
def test_compare_writes_table_csv_json_and_plot(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    result = CliRunner().invoke(
        app,
        [
            "compare",
            str(EXAMPLES / "paper/desk_lamp.yaml"),
            "--planners",
            "fd,mdp,up:pyperplan",
            "--synthetic",
            "6",
            "--out",
            str(tmp_path),
        ],
    )
    assert result.exit_code == 0, result.output
    assert "paper/desk_lamp" in result.stdout and "synthetic-6" in result.stdout
    rows = list(csv.DictReader((tmp_path / "compare.csv").open()))
    assert [(row["task"], row["planner"]) for row in rows] == [
        ("paper/desk_lamp", "fd"),
        ("paper/desk_lamp", "mdp"),
        ("paper/desk_lamp", "up:pyperplan"),
        ("synthetic-6", "fd"),
        ("synthetic-6", "mdp"),
        ("synthetic-6", "up:pyperplan"),
    ]
    assert all(row["status"] == "solved" and row["valid"] == "True" for row in rows), rows
    assert {row["plan_length"] for row in rows[:3]} == {"1"}
    data = json.loads((tmp_path / "compare.json").read_text())
    assert data["settings"]["planners"] == ["fd", "mdp", "up:pyperplan"]
    assert data["settings"]["val"] is True
    assert (tmp_path / "compare.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
def test_every_plan_of_a_comparison_is_checked_by_replay_and_val_and_up_plans_by_up_too() -> None:
    record = run_once(tasks.synthetic(6), "fd", time_limit=30.0, memory_mb=4096, val=True)
    assert record["validated_by"] == {"replay": "valid", "val": "valid"}
    assert run_once(tasks.synthetic(6), "fd", 30.0, 4096)["validated_by"] == {"replay": "valid"}
    record = run_once(tasks.synthetic(6), "up:pyperplan", 30.0, 4096)
    assert record["validated_by"] == {"replay": "valid", "up": "valid"}


@pytest.mark.slow
def test_a_planner_that_runs_out_of_time_is_a_row_not_a_crash() -> None:
    task = tasks.synthetic(80)
    rows = compare([task], ["fd-opt", "fd"], time_limit=1.0, memory_mb=4096, repeat=1)
    assert [(row.planner, row.status) for row in rows] == [("fd-opt", "timeout"), ("fd", "solved")]


def _parent_of(pid: int) -> int | None:
    try:
        return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
    except (OSError, IndexError, ValueError):
        return None


def _grandchildren() -> list[int]:
    """Return the processes whose parent is a child of this one: the runs the fork server forked."""
    pids = [int(name) for name in os.listdir("/proc") if name.isdigit()]
    children = {pid for pid in pids if _parent_of(pid) == os.getpid()}
    return [pid for pid in pids if _parent_of(pid) in children]


def test_a_run_whose_process_dies_is_a_row_not_a_crash() -> None:
    # As the kernel's out-of-memory killer would end it: the run is killed while the MDP (in its process) works.
    records: list[dict[str, object]] = []
    before = set(_grandchildren())
    running = threading.Thread(target=lambda: records.append(run_once(tasks.synthetic(60), "mdp", 60.0, 4096)))
    running.start()
    deadline = time.monotonic() + 30
    while not (runs := [pid for pid in _grandchildren() if pid not in before]) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert len(runs) == 1
    os.kill(runs[0], signal.SIGKILL)
    running.join(60)
    assert records == [{"status": "error", "message": "the worker failed: exit code -9"}]


def test_repeats_report_medians() -> None:
    rows = compare([tasks.synthetic(5)], ["mdp"], time_limit=10.0, memory_mb=4096, repeat=3)
    assert rows[0].repeats == 3 and rows[0].seconds is not None


def test_task_files_and_default_tasks(tmp_path: Path) -> None:
    task_file = tmp_path / "task.yaml"
    task_file.write_text(
        f"model: {EXAMPLES / 'paper/desk_lamp.yaml'}\nmapping: {EXAMPLES / 'paper/flashlight_mapping.yaml'}\n"
    )
    task = tasks.from_argument(task_file, [])
    assert task.name == "paper/desk_lamp -> paper/flashlight_mapping" and task.parts == 3
    assert len(tasks.default_tasks(ROOT)) == len(tasks.DEFAULT_TASKS)
    with pytest.raises(CausalPlanError, match="not under"):
        tasks.default_tasks(tmp_path)
    with pytest.raises(CausalPlanError, match="2 to 400"):
        tasks.synthetic(1)


def test_bad_arguments_are_clear_errors(tmp_path: Path) -> None:
    runner = CliRunner()
    result = runner.invoke(app, ["compare", "--planners", "fd,magic"])
    assert result.exit_code == 2 and "Unknown planner 'magic'" in result.stderr
    result = runner.invoke(app, ["compare", "--synthetic", "ten"])
    assert result.exit_code == 2 and "whole numbers" in result.stderr
    result = runner.invoke(app, ["compare", str(tmp_path / "missing.yaml")])
    assert result.exit_code == 2 and "There is no file" in result.stderr
    assert "Traceback" not in result.output


def test_fd_runs_under_a_worker_memory_limit_below_its_own_default() -> None:
    # FD asks for 2048 MB; inside a 1024 MB worker it must take the lower limit, not fail.
    record = run_once(tasks.synthetic(10), "fd", time_limit=10.0, memory_mb=1024)
    assert record["status"] == "solved", record
