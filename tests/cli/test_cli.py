"""The ``causalplan`` command line: exit codes, JSON shapes, and messages people can act on."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner, Result

from causalplan.cli import app
from tests.conftest import EXAMPLES, ROOT

DESK_LAMP = EXAMPLES / "paper" / "desk_lamp.yaml"
FAILED_DESK_LAMP = EXAMPLES / "paper" / "failed_desk_lamp.yaml"
FLASHLIGHT_MAPPING = EXAMPLES / "paper" / "flashlight_mapping.yaml"
FAILED_FLASHLIGHT_MAPPING = EXAMPLES / "paper" / "failed_flashlight_mapping.yaml"
USER_CATALOG = EXAMPLES / "catalog"
BEDSIDE_MAPPING = EXAMPLES / "user" / "bedside_lamp_mapping.yaml"

# No colours, and wide enough that tables do not wrap ids.
runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "200"})

UNCAUSED_MODEL = """\
object: desk_lamp
functions:
  base_with_cables: [provide electricity]
  light_bulb: [turn electricity into light]
rules:
  - current AND turn electricity into light CAUSES light
"""

MALFORMED_MODEL = """\
object: desk_lamp
functions:
  light_bulb: [turn electricity into light]
\tbase_with_cables: [provide electricity]
rules:
  - provide electricity AND turn electricity into light CAUSES light
"""


def run(*args: object) -> Result:
    return runner.invoke(app, [str(arg) for arg in args])


def run_json(*args: object) -> tuple[int, dict[str, Any]]:
    result = run(*args, "--json")
    return result.exit_code, json.loads(result.stdout)


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def assert_no_traceback(result: Result) -> None:
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)


# --- a real process ------------------------------------------------------------------------------


def causalplan_executable() -> str:
    found = shutil.which("causalplan") or str(Path(sys.executable).parent / "causalplan")
    assert Path(found).exists(), "the causalplan console script is installed with the package"
    return found


def test_plan_desk_lamp_as_a_real_process() -> None:
    environment = {key: value for key, value in os.environ.items() if key != "FORCE_COLOR"}
    completed = subprocess.run(
        [causalplan_executable(), "plan", "examples/paper/desk_lamp.yaml"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        env=environment,
        check=False,
    )
    assert completed.returncode == 0, completed.stderr
    assert "Screw the light bulb into the base with cables." in completed.stdout
    assert "Traceback" not in completed.stderr


HEAVY_MODULES = (
    "typer",
    "rich",
    "pydantic",
    "networkx",
    "numpy",
    "matplotlib",
    "unified_planning",
    "pybullet",
    "fastapi",
)
IMPORTS_OF_A_PLAN = """
import sys
from causalplan.cli import main
heavy = sys.argv[2:]
sys.argv = ["causalplan", "plan", sys.argv[1]]
try:
    main()
except SystemExit as exc:
    code = exc.code
print(code, sorted(name for name in heavy if name in sys.modules))
"""


def test_plan_imports_only_what_it_needs() -> None:
    """`causalplan plan` loads none of the heavy libraries: each costs 20-200 ms per run (issue 8)."""
    completed = subprocess.run(
        [sys.executable, "-c", IMPORTS_OF_A_PLAN, str(DESK_LAMP), *HEAVY_MODULES],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert completed.stdout.strip().splitlines()[-1] == "0 []", completed.stderr


def test_help_lists_the_commands() -> None:
    result = run("--help")
    assert result.exit_code == 0
    for command in ("check", "plan", "transfer", "compile", "objects"):
        assert command in result.output


def test_version_is_the_installed_packages() -> None:
    from importlib.metadata import version

    result = run("--version")
    assert result.exit_code == 0
    assert result.output == f"causalplan {version('causalplan')}\n"
    assert run("-V").output == result.output


# --- check ----------------------------------------------------------------------------------------


def test_check_valid_model_json() -> None:
    code, data = run_json("check", DESK_LAMP)
    assert code == 0
    assert data == {"file": str(DESK_LAMP), "kind": "model", "valid": True, "errors": [], "warnings": []}


def test_check_valid_model_text() -> None:
    result = run("check", DESK_LAMP)
    assert result.exit_code == 0
    assert "model is valid (0 error(s), 0 warning(s))" in result.stdout


def test_check_invalid_model_json(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", UNCAUSED_MODEL)
    code, data = run_json("check", path)
    assert code == 2
    assert set(data) == {"file", "kind", "valid", "errors", "warnings"}
    assert data["valid"] is False
    assert data["kind"] == "model"
    errors = data["errors"]
    assert isinstance(errors, list)
    assert [error["code"] for error in errors] == ["uncaused_effect"]
    error = errors[0]
    assert set(error) == {"code", "severity", "message", "location", "hint"}
    assert error["severity"] == "error"
    assert error["location"] == {"file": str(path), "line": 6, "rule": 1}
    assert "add a rule that causes it" in error["hint"]
    [warning] = data["warnings"]
    assert warning["code"] == "unused_function"
    assert warning["severity"] == "warning"
    assert warning["location"] == {"file": str(path), "line": 3, "part": "base_with_cables"}


def test_check_invalid_model_text_says_where_and_how(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", UNCAUSED_MODEL)
    result = run("check", path)
    assert result.exit_code == 2
    assert f"error[uncaused_effect] {path}, line 6, rule 1:" in result.output
    assert "hint:" in result.output
    assert "model is invalid (1 error(s), 1 warning(s))" in result.output


def test_check_warnings_keep_exit_zero(tmp_path: Path) -> None:
    text = FAILED_DESK_LAMP.read_text(encoding="utf-8").replace(" AND diffuse light", "")
    path = write(tmp_path, "model.yaml", text)
    code, data = run_json("check", path)
    assert code == 0
    assert data["valid"] is True
    assert [warning["code"] for warning in data["warnings"]] == ["unused_function"]


def test_check_mapping_file() -> None:
    code, data = run_json("check", "--kind", "mapping", FLASHLIGHT_MAPPING)
    assert code == 0
    assert data["kind"] == "mapping"
    assert data["valid"] is True


def test_check_invalid_mapping_file(tmp_path: Path) -> None:
    path = write(tmp_path, "mapping.yaml", "object: flashlight\nfunctions:\n  bateries: [provide electricity]\n")
    code, data = run_json("check", "--kind", "mapping", path)
    assert code == 2
    assert data["kind"] == "mapping"
    assert [error["code"] for error in data["errors"]] == ["unknown_part"]
    assert data["errors"][0]["hint"] == "Did you mean 'batteries'?"


def test_check_json_model_file(tmp_path: Path) -> None:
    model = {"object": "candle", "functions": {"wick": ["burn"]}, "rules": ["burn CAUSES light"]}
    path = write(tmp_path, "model.json", json.dumps(model, indent=2))
    code, data = run_json("check", path)
    assert code == 0
    assert data["valid"] is True


def test_check_malformed_yaml_gives_line_without_traceback(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", MALFORMED_MODEL)
    result = run("check", path)
    assert result.exit_code == 2
    assert "syntax_error" in result.output
    assert "line 4" in result.output
    assert_no_traceback(result)


def test_check_malformed_yaml_json_output(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", MALFORMED_MODEL)
    code, data = run_json("check", path)
    assert code == 2
    assert [error["code"] for error in data["errors"]] == ["syntax_error"]
    assert data["errors"][0]["location"] == {"file": str(path), "line": 4}


def test_check_missing_file(tmp_path: Path) -> None:
    result = run("check", tmp_path / "nowhere.yaml")
    assert result.exit_code == 2
    assert "file_not_found" in result.output
    assert_no_traceback(result)


# --- plan -----------------------------------------------------------------------------------------


def test_plan_desk_lamp_text() -> None:
    result = run("plan", DESK_LAMP)
    assert result.exit_code == 0
    assert "1. Screw the light bulb into the base with cables." in result.stdout


def test_plan_json_keys() -> None:
    code, data = run_json("plan", DESK_LAMP)
    assert code == 0
    assert {"status", "planner_used", "plan", "valid_under_model", "valid_under_true_mechanism", "timing"} <= set(data)
    assert "pddl" not in data
    assert data["status"] == "solved"
    assert data["planner_used"] == "fd"
    assert data["valid_under_model"] is True
    assert data["valid_under_true_mechanism"] is True
    plan = data["plan"]
    assert isinstance(plan, list) and len(plan) == 1
    step = plan[0]
    assert {"action", "args", "text"} <= set(step)
    assert step["action"] == "screw"
    assert step["args"] == ["light_bulb", "base_with_cables"]
    assert step["text"] == "Screw the light bulb into the base with cables."
    timing = data["timing"]
    assert {"compile", "translate", "search", "replay", "val", "total"} <= set(timing)
    stages = [seconds for stage, seconds in timing.items() if stage != "total"]
    assert all(isinstance(seconds, float) and seconds > 0 for seconds in stages)
    assert sum(stages) <= timing["total"]  # the stages run one after another, inside the total
    assert data["validated_by"] == {"replay": "valid", "val": "valid"}


def test_plan_and_transfer_check_with_val_unless_told_not_to() -> None:
    _code, unchecked = run_json("plan", DESK_LAMP, "--no-val")
    assert unchecked["validated_by"] == {"replay": "valid"} and "val" not in unchecked["timing"]
    assert "Checked by val valid." in run("plan", DESK_LAMP).stdout
    code, verdict = run_json("transfer", DESK_LAMP, FLASHLIGHT_MAPPING)
    assert code == 0 and verdict["planning"]["validated_by"] == {"replay": "valid", "val": "valid"}
    _code, verdict = run_json("transfer", DESK_LAMP, FLASHLIGHT_MAPPING, "--no-val")
    assert verdict["planning"]["validated_by"] == {"replay": "valid"}


def test_plan_failed_desk_lamp_also_clips_the_shade() -> None:
    # 'diffuse light' was made necessary: the plan must put the shade on, after the bulb.
    code, data = run_json("plan", FAILED_DESK_LAMP)
    assert code == 0
    assert [step["args"][0] for step in data["plan"]] == ["light_bulb", "shade"]


def test_plan_with_mapping_plans_for_the_flashlight() -> None:
    code, data = run_json("plan", DESK_LAMP, "--mapping", FLASHLIGHT_MAPPING)
    assert code == 0
    assert data["object"] == "flashlight"
    moved = {step["args"][0] for step in data["plan"]}
    assert {"batteries", "head"} <= moved
    assert data["valid_under_true_mechanism"] is True


def test_plan_with_failed_mapping_has_no_plan() -> None:
    code, data = run_json("plan", DESK_LAMP, "--mapping", FAILED_FLASHLIGHT_MAPPING)
    assert code == 1
    assert data["status"] == "unsolvable"
    assert data["plan"] is None


def test_plan_pddl_out_writes_domain_and_problem(tmp_path: Path) -> None:
    out = tmp_path / "pddl"
    result = run("plan", DESK_LAMP, "--pddl-out", out)
    assert result.exit_code == 0
    domain = (out / "domain.pddl").read_text(encoding="utf-8")
    problem = (out / "problem.pddl").read_text(encoding="utf-8")
    assert "(define (domain" in domain and ":derived" in domain
    assert "(define (problem" in problem


def test_plan_fd_opt() -> None:
    code, data = run_json("plan", DESK_LAMP, "--planner", "fd-opt")
    assert code == 0
    assert data["planner_used"] == "fd-opt"
    assert len(data["plan"]) == 1


def test_plan_unknown_planner_is_exit_2_with_the_choices() -> None:
    result = run("plan", DESK_LAMP, "--planner", "nope")
    assert result.exit_code == 2
    assert "Unknown planner 'nope'; choose one of: auto, fd, fd-opt, mdp, mdp-exact, up:fast-downward" in result.stderr
    assert_no_traceback(result)


def test_plan_invalid_model_is_exit_2(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", UNCAUSED_MODEL)
    result = run("plan", path)
    assert result.exit_code == 2
    assert "uncaused_effect" in result.stderr
    assert "nothing to plan" in result.stderr


def test_plan_invalid_model_json(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", UNCAUSED_MODEL)
    code, data = run_json("plan", path)
    assert code == 2
    assert data["status"] == "invalid"
    assert data["valid"] is False
    assert [error["code"] for error in data["errors"]] == ["uncaused_effect"]


def test_plan_malformed_yaml_gives_line_without_traceback(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", MALFORMED_MODEL)
    result = run("plan", path)
    assert result.exit_code == 2
    assert "line 4" in result.output
    assert_no_traceback(result)


# --- transfer ---------------------------------------------------------------------------------------


def test_transfer_paper_pair_transfers() -> None:
    result = run("transfer", DESK_LAMP, FLASHLIGHT_MAPPING)
    assert result.exit_code == 0
    assert "transfers: desk_lamp → flashlight (near-generalization)" in result.stdout


def test_transfer_json_keys() -> None:
    code, data = run_json("transfer", DESK_LAMP, FLASHLIGHT_MAPPING)
    assert code == 0
    assert {"verdict", "plan", "generalization", "reasons"} <= set(data)
    assert data["verdict"] == "transfers"
    assert data["generalization"] == "near"
    assert data["training_object"] == "desk_lamp"
    assert data["test_object"] == "flashlight"
    assert data["reasons"] == []
    plan = data["plan"]
    assert isinstance(plan, list) and plan
    assert all({"action", "args", "text"} <= set(step) for step in plan)


def test_transfer_paper_failed_pair_names_both_reasons() -> None:
    code, data = run_json("transfer", FAILED_DESK_LAMP, FAILED_FLASHLIGHT_MAPPING)
    assert code == 1
    assert data["verdict"] == "fails"
    assert data["plan"] is None
    reasons = data["reasons"]
    assert isinstance(reasons, list)
    assert all({"code", "severity"} <= set(reason) for reason in reasons)
    found = {(reason["code"], reason["severity"], tuple(reason["labels"])) for reason in reasons}
    assert ("missing_function", "error", ("turn electricity into light",)) in found
    assert ("unmodelled_function", "warning", ("hold things together",)) in found


def test_transfer_paper_failed_pair_text() -> None:
    result = run("transfer", FAILED_DESK_LAMP, FAILED_FLASHLIGHT_MAPPING)
    assert result.exit_code == 1
    assert "missing_function" in result.stdout and "'turn electricity into light'" in result.stdout
    assert "unmodelled_function" in result.stdout and "'hold things together'" in result.stdout


def test_transfer_invalid_model_is_exit_2(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", UNCAUSED_MODEL)
    code, data = run_json("transfer", path, FLASHLIGHT_MAPPING)
    assert code == 2
    assert data["verdict"] == "invalid"
    assert [reason["code"] for reason in data["reasons"]] == ["invalid_model"]


def test_transfer_invalid_mapping_is_exit_2(tmp_path: Path) -> None:
    path = write(tmp_path, "mapping.yaml", "object: flashlight\nfunctions:\n  bateries: [provide electricity]\n")
    code, data = run_json("transfer", DESK_LAMP, path)
    assert code == 2
    assert [reason["code"] for reason in data["reasons"]] == ["invalid_mapping"]


def test_transfer_malformed_model_gives_line_without_traceback(tmp_path: Path) -> None:
    path = write(tmp_path, "model.yaml", MALFORMED_MODEL)
    result = run("transfer", path, FLASHLIGHT_MAPPING)
    assert result.exit_code == 2
    assert "line 4" in result.output
    assert_no_traceback(result)


def test_transfer_unknown_planner_is_exit_2_with_the_choices() -> None:
    result = run("transfer", DESK_LAMP, FLASHLIGHT_MAPPING, "--planner", "nope")
    assert_no_traceback(result)
    assert result.exit_code == 2
    assert "Unknown planner 'nope'" in result.output


@pytest.mark.parametrize(
    ("model", "mapping", "verdict", "generalization", "reason"),
    [
        ("far/abstract_desk_lamp.yaml", "far/candle_mapping.yaml", "transfers", "far", None),
        (
            "paper/desk_lamp.yaml",
            "far/candle_mapping_for_paper_desk_lamp.yaml",
            "fails",
            "far",
            "violates_true_mechanism",
        ),
        ("near/candle.yaml", "far/flashlight_mapping_for_candle.yaml", "fails", "far", "missing_function"),
        ("near/candle.yaml", "near/kerosene_lamp_mapping.yaml", "transfers", "near", None),
    ],
)
def test_transfer_near_and_far_examples(
    model: str, mapping: str, verdict: str, generalization: str, reason: str | None
) -> None:
    code, data = run_json("transfer", EXAMPLES / model, EXAMPLES / mapping)
    assert data["verdict"] == verdict
    assert data["generalization"] == generalization
    assert code == (0 if verdict == "transfers" else 1)
    codes = [item["code"] for item in data["reasons"]]
    if reason is None:
        assert data["plan"]
        assert not [item for item in data["reasons"] if item["severity"] == "error"]
    else:
        assert reason in codes


def test_transfer_to_kerosene_lamp_screws_the_burner_on_first() -> None:
    _, data = run_json("transfer", EXAMPLES / "near" / "candle.yaml", EXAMPLES / "near" / "kerosene_lamp_mapping.yaml")
    moved = [step["args"][0] for step in data["plan"]]
    assert moved.index("burner") < moved.index("wick")


def test_transfer_of_paper_desk_lamp_to_candle_plans_but_candle_stays_dark() -> None:
    _, data = run_json("transfer", DESK_LAMP, EXAMPLES / "far" / "candle_mapping_for_paper_desk_lamp.yaml")
    assert [step["args"][0] for step in data["plan"]] == ["wick"]


# --- objects and catalogs ----------------------------------------------------------------------------


BUILTIN_CATEGORIES = {
    "desk_lamp": "electric",
    "flashlight": "electric",
    "candle": "combustion",
    "kerosene_lamp": "combustion",
    "headlamp": "electric",
    "solar_lantern": "electric",
    "oil_lamp": "combustion",
    "gas_lantern": "combustion",
    "toy_car": "mechanical",
}


def test_objects_lists_the_builtin_catalog() -> None:
    result = run("objects")
    assert result.exit_code == 0
    for object_id, category in BUILTIN_CATEGORIES.items():
        line = next(line for line in result.stdout.splitlines() if f" {object_id} " in line)
        assert category in line


def test_objects_json() -> None:
    result = run("objects", "--json")
    assert result.exit_code == 0
    data = json.loads(result.stdout)
    assert {item["id"]: item["category"] for item in data} == BUILTIN_CATEGORIES
    desk_lamp = next(item for item in data if item["id"] == "desk_lamp")
    assert set(desk_lamp) == {"id", "name", "category", "goal", "parts"}
    assert {part["id"] for part in desk_lamp["parts"]} == {"shade", "light_bulb", "base_with_cables"}
    flashlight = next(item for item in data if item["id"] == "flashlight")
    assert {part["id"] for part in flashlight["parts"]} == {"case", "head", "batteries"}


def test_objects_desk_lamp_in_detail() -> None:
    result = run("objects", "desk_lamp")
    assert result.exit_code == 0
    assert "desk lamp (desk_lamp, electric, goal: light)" in result.stdout
    for part in ("base_with_cables", "light_bulb", "shade"):
        assert part in result.stdout
    assert "True mechanism:" in result.stdout


def test_objects_desk_lamp_json() -> None:
    result = run("objects", "desk_lamp", "--json")
    assert result.exit_code == 0
    data = json.loads(result.stdout)
    assert data["id"] == "desk_lamp"
    assert data["category"] == "electric"
    assert data["base"] == "base_with_cables"


def test_objects_unknown_id_suggests_the_close_one() -> None:
    result = run("objects", "desk_lmap")
    assert result.exit_code == 2
    assert "Did you mean 'desk_lamp'?" in result.stderr
    assert_no_traceback(result)


def test_catalog_folder_adds_the_user_objects() -> None:
    result = run("objects", "--json", "--catalog", USER_CATALOG)
    assert result.exit_code == 0
    categories = {item["id"]: item["category"] for item in json.loads(result.stdout)}
    assert categories == {**BUILTIN_CATEGORIES, "bedside_lamp": "electric", "worn_lamp": "electric"}


def test_transfer_to_bedside_lamp_has_no_assembly_sequence() -> None:
    code, data = run_json("transfer", DESK_LAMP, BEDSIDE_MAPPING, "--catalog", USER_CATALOG)
    assert code == 1
    assert data["verdict"] == "fails"
    assert data["test_object"] == "bedside_lamp"
    assert [reason["code"] for reason in data["reasons"]] == ["no_assembly_sequence"]


def test_bedside_mapping_without_its_catalog_is_invalid() -> None:
    code, data = run_json("transfer", DESK_LAMP, BEDSIDE_MAPPING)
    assert code == 2
    assert data["verdict"] == "invalid"


def test_missing_catalog_folder_is_exit_2(tmp_path: Path) -> None:
    folder = tmp_path / "no_such_folder"
    result = run("objects", "--catalog", folder)
    assert result.exit_code == 2
    assert "catalog_error" in result.stderr
    assert str(folder) in result.stderr
    assert_no_traceback(result)


def test_malformed_object_file_is_exit_2_naming_file_and_line(tmp_path: Path) -> None:
    path = write(tmp_path, "lamp.yaml", "id: lamp\nname: [unclosed\ncategory: electric\n")
    result = run("objects", "--catalog", tmp_path)
    assert result.exit_code == 2
    assert "catalog_error" in result.stderr
    assert "line" in result.stderr
    assert str(path) in result.stderr
    assert_no_traceback(result)


def test_object_file_missing_fields_is_exit_2(tmp_path: Path) -> None:
    path = write(tmp_path, "lamp.yaml", "id: lamp\nname: lamp\n")
    result = run("check", DESK_LAMP, "--catalog", tmp_path)
    assert result.exit_code == 2
    assert str(path) in result.stderr
    assert "parts" in result.stderr
    assert_no_traceback(result)


def test_object_whose_fit_joins_different_specs_is_exit_2(tmp_path: Path) -> None:
    text = (USER_CATALOG / "bedside_lamp.yaml").read_text(encoding="utf-8")
    cool_bulb = "name: cool bulb\n    connectors:\n      - {id: thread, kind: screw base, spec: E14}"
    assert cool_bulb in text
    path = write(tmp_path, "bedside_lamp.yaml", text.replace(cool_bulb, cool_bulb.replace("E14", "E27")))
    result = run("transfer", DESK_LAMP, BEDSIDE_MAPPING, "--catalog", tmp_path)
    assert result.exit_code == 2
    assert str(path) in result.stderr
    assert "cool_bulb_into_socket" in result.stderr
    assert "E27" in result.stderr and "E14" in result.stderr
    assert_no_traceback(result)


def test_object_id_clashing_with_builtin_is_exit_2(tmp_path: Path) -> None:
    text = (USER_CATALOG / "bedside_lamp.yaml").read_text(encoding="utf-8").replace("id: bedside_lamp", "id: candle")
    write(tmp_path, "candle.yaml", text)
    result = run("objects", "--catalog", tmp_path)
    assert result.exit_code == 2
    assert "already defined" in result.stderr
    assert_no_traceback(result)


# --- compile ------------------------------------------------------------------------------------------


def test_compile_writes_domain_and_problem(tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = run("compile", DESK_LAMP, "--out", out)
    assert result.exit_code == 0
    assert "Wrote" in result.stdout
    domain = (out / "domain.pddl").read_text(encoding="utf-8")
    assert "(:derived" in domain
    assert "desk_lamp" in domain.replace("-", "_")
    assert "(define (problem" in (out / "problem.pddl").read_text(encoding="utf-8")


def test_compile_with_mapping_compiles_for_the_new_object(tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = run("compile", DESK_LAMP, "--mapping", FLASHLIGHT_MAPPING, "--out", out)
    assert result.exit_code == 0
    domain = (out / "domain.pddl").read_text(encoding="utf-8")
    assert "flashlight" in domain
    assert "batteries" in domain


def test_compile_matches_plan_pddl_out(tmp_path: Path) -> None:
    assert run("compile", DESK_LAMP, "--out", tmp_path / "compiled").exit_code == 0
    assert run("plan", DESK_LAMP, "--pddl-out", tmp_path / "planned").exit_code == 0
    for name in ("domain.pddl", "problem.pddl"):
        compiled = (tmp_path / "compiled" / name).read_text(encoding="utf-8")
        assert compiled == (tmp_path / "planned" / name).read_text(encoding="utf-8")


def test_compile_invalid_model_writes_nothing(tmp_path: Path) -> None:
    model = write(tmp_path, "model.yaml", UNCAUSED_MODEL)
    out = tmp_path / "out"
    result = run("compile", model, "--out", out)
    assert result.exit_code == 2
    assert not out.exists()


def test_compile_without_out_is_a_usage_error() -> None:
    result = run("compile", DESK_LAMP)
    assert result.exit_code == 2
    assert "--out" in result.output


def test_planners_lists_every_planner_and_says_whether_val_can_run() -> None:
    result = run("planners")
    assert result.exit_code == 0
    assert "fd-opt" in result.stdout and "up:pyperplan" in result.stdout
    assert "VAL, which checks every plan (--no-val skips it): yes" in result.stdout


def test_check_and_plan_exit_2_naming_the_line_of_a_number_too_long_to_read(tmp_path: Path) -> None:
    model = tmp_path / "model.yaml"
    model.write_text((EXAMPLES / "paper" / "desk_lamp.yaml").read_text() + f"\nextra: {'9' * 5000}\n")
    line = model.read_text().count("\n")
    for command in ("check", "plan"):
        result = run(command, model)
        assert result.exit_code == 2, result.output
        assert f"error[number_too_long] {model}, line {line}" in result.output


# --- one exit-code table ----------------------------------------------------------------------------


def test_the_help_and_the_readme_give_one_exit_code_table() -> None:
    from causalplan.cli.common import EXIT_CODES

    said = " ".join(run("--help").output.split())
    assert EXIT_CODES in said
    assert "0 done (yes), 1 no (" in EXIT_CODES and "2 invalid input, 3 could not decide" in EXIT_CODES
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    table = readme[readme.index("## Exit codes") :].split("\n## ")[0]
    rows = [line.split("|")[1:3] for line in table.splitlines() if line.startswith("| ") and line[2].isdigit()]
    assert [(code.strip(), means.strip()) for code, means in rows] == [
        ("0", "done, yes"),
        ("1", "no"),
        ("2", "invalid input"),
        ("3", "could not decide"),
    ]


def test_readmes_explain_why_runs_on_readmes_model() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    command = next(line for line in readme.splitlines() if line.startswith("$ causalplan explain"))
    # the README's paths are from the repository's root: made absolute, not by changing the process's folder
    arguments = [str(ROOT / word) if word.startswith("examples/") else word for word in command.split()[2:]]
    result = runner.invoke(app, arguments, catch_exceptions=False)
    assert result.exit_code == 0, result.output
    assert "Why step 1?" in result.stdout
