"""`causalplan analyze --near-misses` on the paper's far design: every failed trial checked, none a bare "0 of 0"."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.cli.test_cli import run


@pytest.mark.slow  # a repair search (many plans) per failed trial
def test_a_synthetic_far_design_study_has_its_near_misses_checked(tmp_path: Path) -> None:
    study = tmp_path / "study.json"
    assert run("synthetic-study", "--n", "1", "--out", study).exit_code == 0
    trials = json.loads(study.read_text(encoding="utf-8"))["trials"]
    assert all(len(trial["training_order"]) == 2 and trial["mapping"] for trial in trials)
    result = run("analyze", study, "--out", tmp_path / "out", "--near-misses", "--json")
    assert result.exit_code == 0, result.output
    found = json.loads(result.stdout)["near_misses"]
    failed = sum(trial["verdict"] == "fails" for trial in trials)
    assert found and sum(counts["failed"] for counts in found) == failed
    for counts in found:
        assert counts["not_checked"] == 0, counts["not_checked_because"]
        assert " 0 of 0 " not in counts["summary"]
