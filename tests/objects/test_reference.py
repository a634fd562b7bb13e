"""The expert's reference model of every catalog object: it checks, plans, transfers to itself, and is built."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

from causalplan.cli import app
from causalplan.objects.catalog import load_catalog
from causalplan.objects.model import Requirement
from causalplan.objects.reference import reference_functions, reference_mapping, reference_model
from tests.conftest import ROOT

CATALOG = load_catalog()
OBJECTS = sorted(CATALOG.objects)
runner = CliRunner(env={"FORCE_COLOR": None, "NO_COLOR": "1", "COLUMNS": "200"})


def invoke(*args: str | Path) -> Result:
    return runner.invoke(app, [str(arg) for arg in args])


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("reference")
    for object_id in OBJECTS:
        result = invoke("objects", object_id, "--reference-model", "--out", folder)
        assert result.exit_code == 0, result.output
    return folder


def test_the_catalog_has_four_objects_of_each_category_that_makes_light() -> None:
    categories = [obj.category for obj in CATALOG.objects.values() if obj.goal == "light"]
    assert categories.count("electric") >= 4
    assert categories.count("combustion") >= 4


def test_each_requirement_is_a_function_carried_by_the_parts_its_fits_attach() -> None:
    lantern = CATALOG.get("solar_lantern")
    functions = reference_functions(lantern)
    assert functions["solar_panel"] == functions["crank_handle"] == ["generate electricity"]
    assert "body" not in functions  # the base is always there: it carries nothing
    model = reference_model(lantern)
    assert model["rules"] == ["store electricity AND turn electricity into light AND generate electricity CAUSES light"]
    assert reference_mapping(lantern) == {"object": "solar_lantern", "functions": functions}


def test_a_requirement_without_an_expert_label_is_worded_without_rule_keywords() -> None:
    candle = CATALOG.get("candle")
    unlabelled = (
        Requirement(("wick_into_wax",), "the wick stands and causes nothing"),
        Requirement(("match_lights_wick",), "the wick stands and causes nothing"),
    )
    functions = reference_functions(type(candle)(**{**candle.__dict__, "mechanism": unlabelled}))
    assert functions == {
        "wick": ["the wick stands plus brings about nothing"],
        "match": ["the wick stands plus brings about nothing (2)"],
    }


def test_a_function_label_with_a_rule_keyword_is_refused(tmp_path: Path) -> None:
    text = (ROOT / "causalplan/objects/data/candle.yaml").read_text(encoding="utf-8")
    (tmp_path / "candle2.yaml").write_text(
        text.replace("id: candle\n", "id: candle2\n").replace("function: light the wick", "function: light AND burn"),
        encoding="utf-8",
    )
    result = invoke("objects", "--catalog", tmp_path)
    assert result.exit_code == 2
    assert "rule keywords AND or CAUSES" in result.output


def test_reference_model_needs_an_object_and_out_needs_the_flag(tmp_path: Path) -> None:
    assert "missing_object" in invoke("objects", "--reference-model").output
    assert "missing_option" in invoke("objects", "candle", "--out", tmp_path).output


def test_without_out_the_model_is_printed_as_yaml_or_json() -> None:
    result = invoke("objects", "headlamp", "--reference-model", "--json")
    assert result.exit_code == 0
    printed = json.loads(result.output)
    assert printed["model"]["functions"]["switch"] == ["close the circuit"]
    assert printed["mapping"]["object"] == "headlamp"
    assert "rules:" in invoke("objects", "headlamp", "--reference-model").output


@pytest.mark.parametrize("object_id", OBJECTS)
def test_the_reference_model_checks_plans_and_transfers_to_its_object(object_id: str, written: Path) -> None:
    model, mapping = written / f"{object_id}.yaml", written / f"{object_id}_mapping.yaml"
    assert invoke("check", model).exit_code == 0
    assert invoke("check", "--kind", "mapping", mapping).exit_code == 0
    planned = invoke("plan", model, "--json")
    assert planned.exit_code == 0, planned.output
    assert json.loads(planned.output)["plan"]
    transferred = invoke("transfer", model, mapping, "--json")
    assert transferred.exit_code == 0, transferred.output
    assert json.loads(transferred.output)["verdict"] == "transfers"


@pytest.mark.slow
@pytest.mark.parametrize("object_id", OBJECTS)
def test_the_robot_builds_the_object_from_its_reference_model(object_id: str, written: Path) -> None:
    result = invoke("simulate", written / f"{object_id}.yaml", "--robot", "--json")
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)
    assert report["produces_goal"] is True
