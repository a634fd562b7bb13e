"""`causalplan transfer --robot` and `batch --robot`: the robot has the last word on a transfer."""

from __future__ import annotations

import json
from pathlib import Path

import yaml
from click.testing import CliRunner

from causalplan.cli import app
from tests.conftest import EXAMPLES

ROBOT = EXAMPLES / "robot"
WALLED_PLATE = ROBOT / "walled_plate.yaml"
LONG_BENCH_MAPPING = ROBOT / "long_bench_mapping.yaml"
CATALOG = ["--catalog", str(ROBOT / "catalog")]
"""The walled plate's model maps onto the long bench, whose peg the arm cannot reach."""

runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "200"})


def test_transfer_without_the_robot_passes_on_paper_and_in_physics() -> None:
    result = runner.invoke(app, ["transfer", str(WALLED_PLATE), str(LONG_BENCH_MAPPING), "--json", *CATALOG])
    assert result.exit_code == 0, result.output
    assert json.loads(result.output)["verdict"] == "transfers"


def test_transfer_robot_fails_a_plan_the_robot_cannot_carry_out_naming_the_step_and_code() -> None:
    args = ["transfer", str(WALLED_PLATE), str(LONG_BENCH_MAPPING), "--robot", "--json", *CATALOG]
    result = runner.invoke(app, args)
    assert result.exit_code == 1, result.output
    verdict = json.loads(result.output)
    assert verdict["verdict"] == "fails" and verdict["decided_by"] == "robot"
    (reason,) = [r for r in verdict["reasons"] if r["code"] == "robot_cannot_execute"]
    assert reason["labels"] == ["step 1", "unreachable"]


def test_batch_robot_judges_each_trial_by_the_robot(tmp_path: Path) -> None:
    model = yaml.safe_load(WALLED_PLATE.read_text())
    mapping = yaml.safe_load(LONG_BENCH_MAPPING.read_text())
    trials = tmp_path / "trials.jsonl"
    trials.write_text(json.dumps({"id": "bench", "model": model, "mapping": mapping}) + "\n")
    out = tmp_path / "out"
    result = runner.invoke(app, ["batch", str(trials), "--robot", "--out", str(out), *CATALOG])
    assert result.exit_code == 0, result.output
    (verdict,) = json.loads((out / "verdicts.json").read_text())
    assert verdict["verdict"] == "fails" and verdict["decided_by"] == "robot"
    assert "robot_cannot_execute" in {reason["code"] for reason in verdict["reasons"]}


def test_batch_robot_on_a_local_cluster_gives_the_robots_verdict(tmp_path: Path) -> None:
    model = yaml.safe_load(WALLED_PLATE.read_text())
    mapping = yaml.safe_load(LONG_BENCH_MAPPING.read_text())
    trials = tmp_path / "trials.jsonl"
    trials.write_text(json.dumps({"id": "bench", "model": model, "mapping": mapping}) + "\n")
    out = tmp_path / "out"
    result = runner.invoke(app, ["batch", str(trials), "--robot", "--workers", "1", "--out", str(out), *CATALOG])
    assert result.exit_code == 0, result.output
    (verdict,) = json.loads((out / "verdicts.json").read_text())
    assert verdict["verdict"] == "fails" and verdict["decided_by"] == "robot"
