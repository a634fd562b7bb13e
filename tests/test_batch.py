"""Batch transfer: unreadable lines are invalid trials, and the fast path equals the plain one."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task
from causalplan.planners.pipeline import plan_task
from causalplan.planners.synthetic import synthetic_task
from causalplan.transfer.batch import evaluate_trial, read_trials, run_batch
from causalplan.transfer.verdict import clear_caches
from tests.conftest import EXAMPLES, example_mapping, example_model
from tests.test_pipeline import PAPER_PLANS

TRIALS = EXAMPLES / "batch" / "trials.jsonl"


def test_the_batch_gives_exactly_the_verdicts_of_one_trial_at_a_time(catalog: Catalog) -> None:
    trials = list(read_trials(TRIALS))
    fast = run_batch(trials, catalog)
    for trial, result in zip(trials, fast, strict=True):
        clear_caches()
        plain = evaluate_trial(trial, catalog, "auto", 30.0, True)
        assert result.verdict.as_dict()["verdict"] == plain.verdict.as_dict()["verdict"], trial.id
        assert result.verdict.as_dict()["reasons"] == plain.verdict.as_dict()["reasons"], trial.id
        assert result.verdict.as_dict()["plan"] == plain.verdict.as_dict()["plan"], trial.id
    assert {result.verdict.decided_by for result in fast} == {"validation", "precheck", "planner"}


def test_unreadable_lines_become_invalid_trials_naming_their_line(tmp_path: Path, catalog: Catalog) -> None:
    results = {result.trial_id: result for result in run_batch(list(read_trials(TRIALS)), catalog)}
    broken = results["line-41"].verdict.as_dict()
    assert broken["verdict"] == "invalid" and "line 41" in broken["reasons"][0]["message"]  # type: ignore[index]
    assert results["entry-42"].verdict.as_dict()["verdict"] == "invalid"
    listing = tmp_path / "trials.json"
    listing.write_text(json.dumps({"not": "a list"}))
    (only,) = read_trials(listing)
    assert "list of trials" in str(only.model)


@pytest.mark.parametrize(("model_file", "mapping_file"), sorted(PAPER_PLANS, key=str))
def test_cached_plans_equal_fresh_plans_on_every_example(
    model_file: str, mapping_file: str | None, catalog: Catalog
) -> None:
    model = example_model(model_file, catalog)
    mapping = example_mapping(mapping_file, catalog) if mapping_file else None
    task = build_task(model, catalog.get(mapping.object_id if mapping else model.object_id), mapping)
    fresh = plan_task(task, "fd")
    cached = plan_task(task, "fd")
    assert "cached" in cached.timing
    assert (cached.status, cached.steps, cached.valid_under_true_mechanism) == (
        fresh.status,
        fresh.steps,
        fresh.valid_under_true_mechanism,
    )


@pytest.mark.parametrize("seed", range(5))
def test_cached_plans_equal_fresh_plans_on_random_synthetic_tasks(seed: int) -> None:
    task = synthetic_task(6 + 7 * seed, seed)
    fresh = plan_task(task, "fd")
    assert plan_task(task, "fd").steps == fresh.steps
    clear_caches()
    assert plan_task(task, "fd").steps == fresh.steps


def test_batch_command_writes_csv_and_json(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["batch", str(TRIALS), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "trials/s" in result.stdout
    rows = list(csv.DictReader((tmp_path / "verdicts.csv").open()))
    assert len(rows) == 42 and {row["verdict"] for row in rows} == {"transfers", "fails", "invalid"}
    assert len(json.loads((tmp_path / "verdicts.json").read_text())) == 42
    missing = CliRunner().invoke(app, ["batch", str(tmp_path / "none.jsonl")])
    assert missing.exit_code == 2 and "There is no file" in missing.stderr
