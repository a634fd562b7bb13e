"""Batch transfer: unreadable lines are invalid trials, and the fast path equals the plain one."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from causalplan import caches
from causalplan.cli import app
from causalplan.comparison.synthetic import synthetic_task
from causalplan.errors import InputFileError
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanResult
from causalplan.transfer import verdict as verdict_module
from causalplan.transfer.batch import (
    csv_to_json_lines,
    evaluate_trial,
    read_trials,
    run_batch,
)
from causalplan.transfer.verdict import Verdict
from tests.conftest import EXAMPLES, example_mapping, example_model
from tests.planners.test_pipeline import PAPER_PLANS

TRIALS = EXAMPLES / "batch" / "trials.jsonl"


def test_the_batch_gives_exactly_the_verdicts_of_one_trial_at_a_time(catalog: Catalog) -> None:
    trials = list(read_trials(TRIALS))
    fast = run_batch(trials, catalog)
    for trial, result in zip(trials, fast, strict=True):
        caches.fresh()
        plain = evaluate_trial(trial, catalog, "auto", 30.0, True)
        assert result.verdict.as_dict()["verdict"] == plain.verdict.as_dict()["verdict"], trial.id
        assert result.verdict.as_dict()["reasons"] == plain.verdict.as_dict()["reasons"], trial.id
        assert result.verdict.as_dict()["plan"] == plain.verdict.as_dict()["plan"], trial.id
    assert {result.verdict.decided_by for result in fast} == {"input", "validation", "precheck", "planner"}


def test_unreadable_lines_become_invalid_trials_naming_their_line_and_problem(tmp_path: Path, catalog: Catalog) -> None:
    trials = {trial.id: trial for trial in read_trials(TRIALS)}
    broken, no_mapping = trials["line-41"], trials["no-mapping"]
    assert (broken.line, broken.model, broken.mapping) == (41, None, None)
    assert broken.problem == "Line 41 could not be read: it is not JSON (Expecting ',' delimiter, column 49)."
    assert (no_mapping.line, no_mapping.problem) == (42, "Line 42 could not be read: it has no 'mapping'.")
    assert trials["p0000"].problem is None
    results = {result.trial_id: result for result in run_batch(list(trials.values()), catalog)}
    for trial_id, problem in (("line-41", broken.problem), ("no-mapping", no_mapping.problem)):
        verdict = results[trial_id].verdict
        assert (verdict.verdict, verdict.decided_by) == (Verdict.INVALID, "input")
        assert [(reason.code, reason.message) for reason in verdict.reasons] == [("unreadable_trial", problem)]
    assert results["line-41"].verdict.as_dict()["diagnostics"] == {
        "input": {
            "valid": False,
            "errors": [
                {"code": "unreadable_trial", "severity": "error", "message": broken.problem, "location": {"line": 41}}
            ],
            "warnings": [],
        }
    }
    listing = tmp_path / "trials.json"
    listing.write_text(json.dumps({"not": "a list"}))
    (only,) = read_trials(listing)
    assert only.problem is not None and "is not a list of trials" in only.problem
    listing.write_text(json.dumps([[], {"model": {}}]))
    assert [trial.problem for trial in read_trials(listing)] == [
        "Entry 1 could not be read: it is not an object with 'model' and 'mapping'.",
        "Entry 2 could not be read: it has no 'mapping'.",
    ]


def test_a_line_that_is_not_utf8_or_too_deep_is_unreadable_and_the_others_are_read(tmp_path: Path) -> None:
    first, second = TRIALS.read_text(encoding="utf-8").splitlines()[:2]
    lines = tmp_path / "trials.jsonl"
    lines.write_bytes(b"\n".join([first.encode(), b'{"id": "\xff"}', b"[" * 100_000, second.encode()]) + b"\n")
    trials = list(read_trials(lines))
    assert [trial.id for trial in trials] == ["p0000", "line-2", "line-3", "p0001"]
    assert trials[1].problem == "Line 2 could not be read: it is not UTF-8 text (byte 8)."
    assert trials[2].problem == "Line 3 could not be read: it is nested too deeply."
    assert trials[3].problem is None and trials[3].line == 4


def test_an_unreadable_line_never_reaches_the_planner_and_the_other_lines_are_judged(
    tmp_path: Path, catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    first, second = TRIALS.read_text(encoding="utf-8").splitlines()[:2]
    lines = tmp_path / "trials.jsonl"
    lines.write_text("\n".join([first, '{"id": "broken", "model": {', '["not", "a", "trial"]', second]) + "\n")
    planned: list[PlanningTask] = []
    real_plan_task = verdict_module.plan_task

    def spy(task: PlanningTask, *args: Any, **kwargs: Any) -> PlanResult:
        planned.append(task)
        return real_plan_task(task, *args, **kwargs)

    monkeypatch.setattr(verdict_module, "plan_task", spy)
    planned_so_far: list[int] = []
    results = run_batch(
        list(read_trials(lines)), catalog, simulate=False, progress=lambda: planned_so_far.append(len(planned))
    )
    assert planned_so_far == [1, 1, 1, 2]  # the planner ran for the first and the last line only
    assert [(result.trial_id, result.verdict.decided_by) for result in results] == [
        ("p0000", "planner"),
        ("line-2", "input"),
        ("entry-3", "input"),
        ("p0001", "planner"),
    ]


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
    caches.fresh()
    assert plan_task(task, "fd").steps == fresh.steps


def test_batch_command_writes_csv_and_json(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["batch", str(TRIALS), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "trials/s" in result.stdout and "input 2" in result.stdout
    rows = list(csv.DictReader((tmp_path / "verdicts.csv").open()))
    assert len(rows) == 42 and {row["verdict"] for row in rows} == {"transfers", "fails", "invalid"}
    unreadable = [row for row in rows if row["decided_by"] == "input"]
    assert [(row["id"], row["verdict"], row["reasons"]) for row in unreadable] == [
        ("line-41", "invalid", "unreadable_trial"),
        ("no-mapping", "invalid", "unreadable_trial"),
    ]
    verdicts = json.loads((tmp_path / "verdicts.json").read_text())
    assert len(verdicts) == 42
    planned = [verdict["planning"] for verdict in verdicts if verdict["plan"] is not None]
    assert planned and all(plan["validated_by"]["val"] == "valid" for plan in planned)
    missing = CliRunner().invoke(app, ["batch", str(tmp_path / "none.jsonl")])
    assert missing.exit_code == 2 and "There is no file" in missing.stderr


def test_the_batch_command_names_ids_that_several_trials_share(tmp_path: Path) -> None:
    first, second = TRIALS.read_text(encoding="utf-8").splitlines()[:2]
    shared = json.dumps({**json.loads(second), "id": "[bold]p0000[/bold]"})  # an id is the file's words, not styles
    trials = tmp_path / "trials.jsonl"
    trials.write_text("\n".join([first, shared, shared, first, first]), encoding="utf-8")
    result = CliRunner().invoke(app, ["batch", str(trials), "--no-simulate", "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    said = " ".join(result.stdout.split())
    assert "warning[duplicate_ids]: 2 trial id(s) are used by more than one trial" in said
    assert "'p0000' (3 trials), '[bold]p0000[/bold]' (2 trials)" in said
    assert len(list(csv.DictReader((tmp_path / "out" / "verdicts.csv").open()))) == 5  # every trial judged


def test_a_trial_whose_plan_val_rejects_is_undecided_and_the_batch_goes_on(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    from dataclasses import replace

    from causalplan.pddl.writer import CompiledTask
    from causalplan.planners import pipeline

    real_compile = pipeline.compile_task

    def negated_goal(task: PlanningTask) -> CompiledTask:  # as a mistranslated rule would read to VAL
        compiled = real_compile(task)
        return replace(compiled, problem=compiled.problem.replace("(:goal (n-light))", "(:goal (not (n-light)))"))

    monkeypatch.setattr(pipeline, "compile_task", negated_goal)
    trials = list(read_trials(TRIALS))
    results = run_batch(trials, catalog, simulate=False, val=True)
    assert len(results) == len(trials)
    rejected = [result.verdict for result in results if result.verdict.decided_by == "validator"]
    assert rejected and all(verdict.verdict is Verdict.UNDECIDED for verdict in rejected)
    assert all(verdict.reasons[0].code == "plan_rejected_by_val" for verdict in rejected)
    assert "Goal not satisfied" in rejected[0].reasons[0].message


# --- numbers too long to read, CSV as spreadsheets write it, ids used twice ------------------------

TOO_LONG = "7" * 5000
"""More digits than Python reads from text (4,300)."""


def test_a_line_with_a_number_too_long_to_read_is_one_invalid_trial(tmp_path: Path, catalog: Catalog) -> None:
    good = TRIALS.read_text().splitlines()[0]
    path = tmp_path / "trials.jsonl"
    path.write_text(good + "\n" + good[:-1] + f', "seed": {TOO_LONG}}}\n' + good + "\n")
    trials = list(read_trials(path))
    assert [trial.problem for trial in trials] == [
        None,
        "Line 2 could not be read: it holds a number of 5,000 digits (at most 4,300 can be read).",
        None,
    ]
    assert [result.verdict.verdict for result in run_batch(trials, catalog, simulate=False)][1] == Verdict.INVALID


def test_batch_of_a_list_file_with_a_number_too_long_names_its_line(tmp_path: Path) -> None:
    path = tmp_path / "trials.json"
    path.write_text('[\n  {"id": "a",\n   "model": {}, "mapping": ' + TOO_LONG + "}\n]\n")
    (only,) = read_trials(path)
    assert only.line == 3 and only.problem is not None and "5,000 digits" in only.problem


def spreadsheet(rows: list[list[str]], newline: str = "\r\n", bom: bool = False) -> str:
    """Return ``rows`` under the header id, model, mapping as a spreadsheet saves CSV."""
    lines = []
    for row in [["id", "model", "mapping"], *rows]:
        lines.append(",".join('"' + cell.replace('"', '""') + '"' for cell in row))
    return ("\ufeff" if bom else "") + newline.join(lines) + newline


ROWS = [["a", '{"object": "desk_lamp"}', '{"object": "flashlight"}'], ["", "{}", "{}"]]
LINES = [
    {"id": "a", "model": {"object": "desk_lamp"}, "mapping": {"object": "flashlight"}},
    {"id": "row-3", "model": {}, "mapping": {}},
]


@pytest.mark.parametrize("newline", ["\r\n", "\n", "\r"], ids=["crlf", "lf", "bare-cr"])
@pytest.mark.parametrize("bom", [False, True], ids=["plain", "bom"])
def test_a_csv_is_read_whatever_its_line_endings_and_byte_order_mark(newline: str, bom: bool) -> None:
    text = spreadsheet(ROWS, newline, bom)
    assert [json.loads(line) for line in csv_to_json_lines(text).splitlines()] == LINES


def test_a_csv_cell_with_a_line_break_inside_quotes_keeps_it() -> None:
    text = spreadsheet([["a", '{"object":\r"desk_lamp"}', "{}"]], "\r")
    assert json.loads(csv_to_json_lines(text))["model"] == {"object": "desk_lamp"}


def test_a_csv_cell_with_a_number_too_long_is_refused_naming_row_and_column() -> None:
    with pytest.raises(InputFileError) as raised:
        csv_to_json_lines(spreadsheet([ROWS[0], ["b", "{}", f'{{"seed": {TOO_LONG}}}']]))
    assert raised.value.details == {"row": 3, "column": "mapping"}
    assert "5,000 digits" in raised.value.message


def test_csv_rows_that_share_an_id_are_named_with_their_rows() -> None:
    with pytest.raises(InputFileError) as raised:
        csv_to_json_lines(spreadsheet([ROWS[0], ["b", "{}", "{}"], ROWS[0]]))
    assert raised.value.details == {"duplicate_ids": {"a": [2, 4]}}
    assert "'a' (rows 2, 4)" in raised.value.message
