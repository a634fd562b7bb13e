"""examples/troubleshooting: each JSON file is what its command prints (golden files)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from causalplan.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
COMMANDS = {
    "desk_lamp_good_model.json": ["paper/desk_lamp.yaml"],
    "desk_lamp_failed_model.json": ["paper/failed_desk_lamp.yaml"],
    "flashlight_near.json": ["paper/desk_lamp.yaml", "-m", "paper/flashlight_mapping.yaml"],
    "candle_far.json": ["paper/desk_lamp.yaml", "-m", "far/candle_mapping_for_paper_desk_lamp.yaml"],
}


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_each_example_is_what_its_command_prints(name: str) -> None:
    paths = [arg if arg.startswith("-") else str(EXAMPLES / arg) for arg in COMMANDS[name]]
    result = CliRunner().invoke(app, ["troubleshoot", *paths, "--all-faults", "--json"])
    assert result.exit_code == 0, result.output
    expected = json.loads((EXAMPLES / "troubleshooting" / name).read_text(encoding="utf-8"))
    assert json.loads(result.output) == expected, f"regenerate examples/troubleshooting/{name} (see its README)"


def test_the_examples_say_what_the_issue_asks() -> None:
    def expected(name: str, strategy: str) -> float:
        data = json.loads((EXAMPLES / "troubleshooting" / name).read_text(encoding="utf-8"))
        return float(data["strategies"][strategy]["expected_actions"])

    good, failed = "desk_lamp_good_model.json", "desk_lamp_failed_model.json"
    assert expected(good, "model") < expected(good, "uniform")
    assert expected(failed, "model") > expected(good, "model")
    for name in COMMANDS:
        assert expected(name, "oracle") <= expected(name, "model")
