"""`causalplan check` and `causalplan graph`: a file is read as the command says, and an invalid model is not drawn."""

from __future__ import annotations

import json
from pathlib import Path

from tests.cli.test_cli import DESK_LAMP, FLASHLIGHT_MAPPING, run, write

RULES_MISSPELLED = DESK_LAMP.read_text(encoding="utf-8").replace("\nrules:", "\nrulez:")
RULES_MISSING = """\
object: desk_lamp
functions:
  base_with_cables: [provide electricity]
  light_bulb: [turn electricity into light]
"""


def test_a_model_whose_rules_key_is_misspelled_is_an_invalid_model_as_plan_says(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", RULES_MISSPELLED)
    checked, planned = run("check", path), run("plan", path)
    assert checked.exit_code == planned.exit_code == 2
    for said in (checked.output, planned.output):
        assert "The model has an unknown field 'rulez'." in said and "Did you mean 'rules'?" in said
    assert "mapping" not in checked.output
    assert f"{path}: model is invalid" in checked.output


def test_a_model_without_rules_is_invalid_and_never_a_valid_mapping(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", RULES_MISSING)
    result = run("check", path, "--json")
    assert result.exit_code == 2
    data = json.loads(result.stdout)
    assert data["kind"] == "model" and data["valid"] is False
    assert "missing_field" in [error["code"] for error in data["errors"]]
    said = run("check", path)
    assert "model is invalid" in said.output and "mapping is valid" not in said.output
    # it has only a mapping's fields: the advice says how to check it as one, and that works
    assert f"causalplan check --kind mapping {path}" in said.output
    as_mapping = run("check", "--kind", "mapping", path)
    assert as_mapping.exit_code == 0 and f"{path}: mapping is valid" in as_mapping.output


def test_a_mapping_is_read_as_a_mapping_only_when_asked(tmp_path: Path) -> None:
    assert run("check", "--kind", "mapping", FLASHLIGHT_MAPPING).exit_code == 0
    as_model = run("check", FLASHLIGHT_MAPPING)
    assert as_model.exit_code == 2 and "The model has no 'rules' field." in as_model.output
    # a model is not a mapping either: its rules are an unknown field of a mapping
    model_as_mapping = run("check", "--kind", "mapping", DESK_LAMP)
    assert model_as_mapping.exit_code == 2 and "The mapping has an unknown field 'rules'" in model_as_mapping.output


def test_check_help_says_the_option_decides_how_a_file_is_read() -> None:
    said = " ".join(run("check", "--help").output.split())
    assert "--kind [model|mapping]" in said
    assert "never the file's contents" in said


def test_graph_of_an_invalid_model_writes_nothing_and_says_why(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", RULES_MISSPELLED)
    for picture in (tmp_path / "graph.png", tmp_path / "graph.dot"):
        result = run("graph", path, "--out", picture)
        assert result.exit_code == 2
        assert not picture.exists()
        assert "Wrote" not in result.output
        assert "Did you mean 'rules'?" in result.stderr and "nothing was drawn" in result.stderr
    to_screen = run("graph", path)
    assert to_screen.exit_code == 2 and to_screen.stdout == ""


def test_graph_of_a_valid_model_is_drawn(tmp_path: Path) -> None:
    picture = tmp_path / "graph.png"
    result = run("graph", DESK_LAMP, "--out", picture)
    assert result.exit_code == 0 and f"Wrote {picture}" in result.stderr
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_graph_refuses_an_unknown_format_before_reading_the_model(tmp_path: Path) -> None:
    result = run("graph", DESK_LAMP, "--out", tmp_path / "graph.bmp")
    assert result.exit_code == 2 and "unknown_format" in result.stderr
    assert not (tmp_path / "graph.bmp").exists()
