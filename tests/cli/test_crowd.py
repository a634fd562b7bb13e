"""The crowd's commands: consensus, population, crowd-curve, through the command line."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from causalplan.cli import app
from tests.conftest import EXAMPLES

runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "200"})
MINORITY_ONLY = [
    "--rate-non-causal",
    "0",
    "--rate-uncaused-intermediate",
    "0",
    "--rate-object-specific",
    "0",
    "--rate-missed-part",
    "0",
    "--rate-effect-as-cause",
    "0.2",
]


def test_population_then_consensus_writes_a_model_that_checks_plans_and_transfers(tmp_path: Path) -> None:
    crowd = tmp_path / "crowd.jsonl"
    made = runner.invoke(
        app, ["population", "desk_lamp", "--n", "12", "--seed", "2", "--out", str(crowd), *MINORITY_ONLY]
    )
    assert made.exit_code == 0, made.output
    assert "Wrote 12 participants (36 trials)" in made.output
    out = tmp_path / "out"
    result = runner.invoke(app, ["consensus", str(crowd), "--out", str(out), "--no-simulate"])
    assert result.exit_code == 0, result.output
    assert sorted(path.name for path in out.iterdir()) == [
        "consensus_graph.png",
        "consensus_graph.svg",
        "consensus_mapping_candle.yaml",
        "consensus_mapping_flashlight.yaml",
        "consensus_mapping_kerosene_lamp.yaml",
        "consensus_model.yaml",
        "report.json",
    ]
    checked = runner.invoke(app, ["check", str(out / "consensus_model.yaml")])
    assert checked.exit_code == 0, checked.output
    moved = runner.invoke(
        app, ["transfer", str(out / "consensus_model.yaml"), str(out / "consensus_mapping_candle.yaml")]
    )
    assert moved.exit_code == 0, moved.output
    report = json.loads((out / "report.json").read_text())
    assert report["participants"] == 12
    assert set(report["consensus_verdict"]) == {"candle", "flashlight", "kerosene_lamp"}
    assert all(verdict["verdict"] == "transfers" for verdict in report["consensus_verdict"].values())
    assert len(report["individual_verdicts"]) == 36
    transferred = sum(v["verdict"] == "transfers" for v in report["individual_verdicts"])
    assert report["individual_transfer_rate"] == transferred / 36
    entered = [rule for rule in report["rules"] if rule["entered"]]
    assert all(rule["support"] >= 0.5 and len(rule["participants"]) == rule["holders"] for rule in entered)


def test_a_crowd_split_three_ways_has_no_consensus_and_the_command_says_why(tmp_path: Path) -> None:
    # The example batch's desk-lamp people hold three different models, none by half of them.
    result = runner.invoke(
        app, ["consensus", str(EXAMPLES / "batch" / "trials.jsonl"), "--out", str(tmp_path), "--no-simulate"]
    )
    assert result.exit_code == 2
    assert "The consensus model is not valid: No rule produces the goal 'light'." in result.output
    assert "the most held: 33%" in result.output and "--min-support 0.33" in result.output
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["training_object"] == "desk_lamp"
    assert report["left_out"]["p0004"] == "trained on candle, the crowd on desk_lamp"
    assert max(rule["support"] for rule in report["rules"]) < 0.5


def test_consensus_says_why_there_is_no_crowd(tmp_path: Path) -> None:
    empty = tmp_path / "empty.jsonl"
    empty.write_text("{broken\n")
    result = runner.invoke(app, ["consensus", str(empty), "--out", str(tmp_path / "out")])
    assert result.exit_code == 2
    assert "no_crowd" in result.output and "line 1 is not a JSON object" in result.output


def test_a_majority_error_that_makes_the_model_invalid_exits_2_and_says_why(tmp_path: Path) -> None:
    crowd = tmp_path / "crowd.jsonl"
    runner.invoke(app, ["population", "candle", "--n", "6", "--out", str(crowd), "--rate-uncaused-intermediate", "1"])
    result = runner.invoke(app, ["consensus", str(crowd), "--out", str(tmp_path / "out"), "--no-simulate"])
    assert result.exit_code == 2
    assert "The consensus model is not valid" in result.output


def test_crowd_curve_runs_on_a_small_population(tmp_path: Path) -> None:
    result = runner.invoke(
        app, ["crowd-curve", "desk_lamp", "--sizes", "1,3", "--draws", "2", "--out", str(tmp_path), "--test", "candle"]
    )
    assert result.exit_code == 0, result.output
    assert "candle (far)" in result.output
    rows = (tmp_path / "curve.csv").read_text().splitlines()
    assert rows[0].startswith("size,test_object,generalization,draws,consensus_rate")
    assert len(rows) == 3
    assert json.loads((tmp_path / "curve.json").read_text())["settings"]["draws"] == 2


def test_crowd_curve_rejects_sizes_that_are_not_numbers(tmp_path: Path) -> None:
    result = runner.invoke(app, ["crowd-curve", "--sizes", "1,a", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert "--sizes must be whole numbers" in result.output


def test_consensus_reads_an_experiment_export(tmp_path: Path) -> None:
    from causalplan.consensus.population import ERROR_KINDS, population

    lines = population("desk_lamp", 3, seed=4, rates=dict.fromkeys(ERROR_KINDS, 0.0), tests=("flashlight",))
    export = {  # the research page's JSON export (studies/export.py): participants, then trials
        "experiment": {"id": "e1", "name": "pilot"},
        "participants": [
            {"participant_id": f"u{n}", "code": f"P-{n}", "model": line["model"]} for n, line in enumerate(lines)
        ],
        "trials": [
            {"participant_id": f"u{n}", "test_object": "flashlight", "mapping": line["mapping"]}
            for n, line in enumerate(lines)
        ],
    }
    path = tmp_path / "export.json"
    path.write_text(json.dumps(export))
    result = runner.invoke(app, ["consensus", str(path), "--out", str(tmp_path / "out"), "--no-simulate"])
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert [rule["participants"] for rule in report["rules"]] == [["P-0", "P-1", "P-2"]] * 2
    assert report["consensus_verdict"]["flashlight"]["verdict"] == "transfers"
    assert report["individual_transfer_rate"] == 1.0


def test_the_commands_default_min_support_is_the_builders() -> None:
    from causalplan.consensus.build import MIN_SUPPORT

    for name in ("consensus", "crowd-curve"):
        (option,) = [param for param in app.commands[name].params if param.name == "min_support"]
        assert option.default == MIN_SUPPORT
