"""`causalplan plan` and `transfer`: the exit-code table, invalid inputs in `check`'s words, repairs counted."""

from __future__ import annotations

import json
from pathlib import Path

import yaml

from causalplan.comparison.synthetic import object_document, synthetic_model, synthetic_object
from tests.cli.test_cli import DESK_LAMP, FAILED_DESK_LAMP, run, write


def write_synthetic(folder: Path, parts: int) -> tuple[Path, Path]:
    """Write a synthetic object (as a catalog folder) and its model; return (catalog folder, model file)."""
    obj = synthetic_object(parts)
    catalog = folder / "catalog"
    catalog.mkdir()
    (catalog / f"{obj.id}.yaml").write_text(yaml.safe_dump(object_document(obj), sort_keys=False), encoding="utf-8")
    model = synthetic_model(obj)
    functions = {part: list(labels) for part, labels in model.labelling.functions.items()}
    data = {"object": obj.id, "goal": model.goal, "functions": functions, "rules": [r.text for r in model.rules]}
    return catalog, write(folder, "model.yaml", yaml.safe_dump(data, sort_keys=False))


def test_plan_exits_3_when_the_planner_times_out(tmp_path: Path) -> None:
    # 320 parts take Fast Downward seconds (docs: 8.8 s); a tenth of a second can never be enough.
    catalog, model = write_synthetic(tmp_path, 320)
    result = run("plan", model, "--catalog", catalog, "--planner", "fd", "--time-limit", "0.1", "--no-val")
    assert result.exit_code == 3, result.output
    assert "No plan (timeout)" in result.stdout
    as_json = run("plan", model, "--catalog", catalog, "--planner", "fd", "--time-limit", "0.1", "--json")
    assert as_json.exit_code == 3 and json.loads(as_json.stdout)["status"] == "timeout"


def test_plan_exits_1_when_there_is_no_plan(tmp_path: Path) -> None:
    mapping = write(tmp_path, "mapping.yaml", "object: flashlight\nfunctions:\n  case: [provide electricity]\n")
    result = run("plan", DESK_LAMP, "--mapping", mapping)
    assert result.exit_code == 1 and "No plan (unsolvable)" in result.stdout


def test_plan_help_gives_every_exit_code() -> None:
    said = " ".join(run("plan", "--help").output.split())
    assert "Exit 0 with a plan, 1 when there is none" in said and "3 when the planner could not decide" in said


def test_transfer_with_a_misspelled_part_keeps_checks_did_you_mean(tmp_path: Path) -> None:
    mapping = write(tmp_path, "mapping.yaml", "object: flashlight\nfunctions:\n  bateries: [provide electricity]\n")
    result = run("transfer", DESK_LAMP, mapping)
    assert result.exit_code == 2
    assert "error[unknown_part]" in result.stdout and "hint: Did you mean 'batteries'?" in result.stdout
    assert f"causalplan check --kind mapping {mapping}" in result.stdout


def test_transfer_never_names_an_object_it_could_not_read(tmp_path: Path) -> None:
    mappings = {
        "no_object.yaml": "functions:\n  batteries: [provide electricity]\n",
        "malformed.yaml": "object: [flashlight\n",
        "misspelled.yaml": "object: flashlite\nfunctions:\n  batteries: [provide electricity]\n",
    }
    for name, text in mappings.items():
        result = run("transfer", DESK_LAMP, write(tmp_path, name, text))
        assert result.exit_code == 2
        assert "None" not in result.output and "→ ," not in result.output, result.output
        assert "invalid: the mapping is invalid, so nothing was planned." in result.stdout
    misspelled = run("transfer", DESK_LAMP, tmp_path / "misspelled.yaml")
    assert "Did you mean 'flashlight'?" in misspelled.stdout


def test_transfer_with_an_invalid_model_says_did_you_mean_rules(tmp_path: Path) -> None:
    model = write(tmp_path, "model.yaml", DESK_LAMP.read_text(encoding="utf-8").replace("\nrules:", "\nrulez:"))
    mapping = write(tmp_path, "mapping.yaml", "object: flashlight\nfunctions:\n  batteries: [provide electricity]\n")
    result = run("transfer", model, mapping)
    assert result.exit_code == 2
    assert "the model is invalid" in result.stdout and "Did you mean 'rules'?" in result.stdout


def test_transfer_repair_says_how_many_of_the_repairs_it_shows(tmp_path: Path) -> None:
    mapping = write(tmp_path, "mapping.yaml", "object: flashlight\nfunctions:\n  batteries: [provide electricity]\n")
    result = run("transfer", FAILED_DESK_LAMP, mapping, "--repair")
    assert result.exit_code == 1
    [summary] = [line for line in result.stdout.splitlines() if line.startswith("Repairs:")]
    found = int(summary.split()[1])
    assert found > 5 and f"5 of {found} shown, smallest first" in summary
    assert len([line for line in result.stdout.splitlines() if line.startswith("  [")]) == 5
