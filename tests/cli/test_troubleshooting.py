"""`causalplan troubleshoot`: one episode, the strategies' table, and clear errors with exit codes."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner, Result

from causalplan.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
LAMP = EXAMPLES / "paper" / "desk_lamp.yaml"
FAILED_LAMP = EXAMPLES / "paper" / "failed_desk_lamp.yaml"
FLASHLIGHT_MAPPING = EXAMPLES / "paper" / "flashlight_mapping.yaml"
runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "200"})


def run(*args: object) -> Result:
    return runner.invoke(app, ["troubleshoot", *(str(arg) for arg in args)])


def run_json(*args: object) -> tuple[int, dict[str, Any]]:
    result = run(*args, "--json")
    return result.exit_code, json.loads(result.output)


def test_one_episode_prints_each_action_with_what_it_showed() -> None:
    result = run(LAMP, "--fault", "light_bulb")
    assert result.exit_code == 0, result.output
    assert "the light bulb is broken (a burnt-out filament)" in result.output
    assert "inspect light_bulb: broken" in result.output
    assert result.output.splitlines()[-2].strip().endswith("test: light")
    assert "Repaired in 7 actions (model 7, uniform 7, oracle 7)." in result.output


def test_an_episode_in_json_lists_the_steps_and_every_strategy_s_actions() -> None:
    code, data = run_json(FAILED_LAMP, "--fault", "base_with_cables", "--strategy", "model")
    assert code == 0
    assert data["status"] == "repaired" and data["fault"] == "base_with_cables"
    assert data["steps"][-1] == {"action": "test", "part": None, "observed": "goal"}
    assert {"action": "replace", "part": "base_with_cables", "observed": None} in data["steps"]
    assert data["actions"] == len(data["steps"]) == data["strategies"]["model"]["actions"]
    assert set(data["strategies"]) == {"model", "uniform", "oracle"}


def test_all_faults_gives_the_strategies_table() -> None:
    code, data = run_json(LAMP, "--all-faults")
    assert code == 0
    strategies = data["strategies"]
    assert set(strategies) == {"model", "uniform", "oracle"}
    for result in strategies.values():
        assert set(result) >= {"expected_actions", "worst_actions", "reward_share", "faults"}
        assert set(result["faults"]) == {"light_bulb", "base_with_cables"}
    assert strategies["model"]["expected_actions"] < strategies["uniform"]["expected_actions"]
    assert data["repair_bonus"] == 20 and data["fault_priors"] == "illustrative"
    table = run(LAMP, "--all-faults")
    assert "Troubleshooting the desk lamp (illustrative priors)" in table.output
    assert "light_bulb (0.7)" in table.output


def test_a_mapped_model_troubleshoots_the_mapping_s_object() -> None:
    code, data = run_json(LAMP, "--mapping", FLASHLIGHT_MAPPING, "--all-faults")
    assert code == 0 and data["object"] == "flashlight"


@pytest.mark.parametrize(
    ("args", "code"),
    [
        ((LAMP, "--fault", "lid"), "unknown_fault_part"),
        ((LAMP, "--fault", "shade"), "fault_not_needed"),
        ((LAMP, "--object", "flashlight", "--all-faults"), "mapping_does_not_fit"),
        (
            (LAMP, "--mapping", EXAMPLES / "paper" / "failed_flashlight_mapping.yaml", "--all-faults"),
            "mapping_does_not_fit",
        ),
        ((LAMP, "--object", "no_such_thing", "--all-faults"), "unknown_object"),
    ],
)
def test_bad_input_exits_2_with_a_code(args: tuple[object, ...], code: str) -> None:
    exit_code, data = run_json(*args)
    assert exit_code == 2
    assert data["error"]["code"] == code


def test_an_object_without_faults_is_refused(tmp_path: Path) -> None:
    import yaml

    lamp = yaml.safe_load((Path(__file__).resolve().parents[2] / "causalplan/objects/data/desk_lamp.yaml").read_text())
    lamp.pop("faults")
    lamp["id"] = "plain_lamp"
    (tmp_path / "plain_lamp.yaml").write_text(yaml.safe_dump(lamp))
    model = tmp_path / "model.yaml"
    model.write_text(LAMP.read_text().replace("object: desk_lamp", "object: plain_lamp"))
    result = run(model, "--all-faults", "--catalog", tmp_path)
    assert result.exit_code == 2
    assert "object_without_faults" in result.output


def test_fault_and_all_faults_go_one_at_a_time() -> None:
    assert run(LAMP).exit_code == 2
    both = run(LAMP, "--fault", "light_bulb", "--all-faults")
    assert both.exit_code == 2 and "missing_option" in both.output
