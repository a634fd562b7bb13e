"""The participant's model and mappings, experiment designs, the graph drawing and the sign-in cookie (no server)."""

from __future__ import annotations

import pytest

from causalplan.causal.diagram import diagram_svg
from causalplan.causal.documents import SourceMap
from causalplan.inputs import model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.service.pages.auth import cookie_session, session_cookie
from causalplan.service.responses import csv_bytes
from causalplan.settings import Settings
from causalplan.studies.design import read_design
from causalplan.studies.errors import InvalidExperimentError
from causalplan.studies.steps import (
    ParticipantModel,
    check_functions,
    check_mapping,
    check_model,
    labels_from_text,
    mapping_document,
    model_on,
    rule_lines,
    rules_from_text,
)
from causalplan.studies.tutorial import EXAMPLE_RULES, QUESTIONS, practice_model, wrong_answers

SETTINGS = Settings(database_url="sqlite://")
DESK_LAMP = {"base_with_cables": ["provide electricity"], "light_bulb": ["turn electricity into light"]}


def test_boxes_become_labels_and_rules_with_their_lines() -> None:
    assert labels_from_text("  provide   electricity \n\n close the circuit\n") == [
        "provide electricity",
        "close the circuit",
    ]
    rules, lines = rules_from_text("\nA CAUSES b\n   \nb CAUSES light\n")
    assert rules == ["A CAUSES b", "b CAUSES light"]
    assert lines == [2, 4]


def test_one_training_object_is_checked_exactly_as_causalplan_check_does(catalog: Catalog) -> None:
    rules = (
        "provide electricity AND turn electricity into light CAUSES electricity flows",
        "electricity flow CAUSES light",
    )
    model = ParticipantModel("light", {"desk_lamp": DESK_LAMP}, rules)
    checked = check_model(model, catalog, SETTINGS)
    reference = model_from_data(model.document("desk_lamp"), SourceMap(), catalog).report
    assert checked.report == reference
    assert not checked.is_valid and checked.report.codes() == ["unknown_cause", "unused_effect"]
    _, lines = rules_from_text("\n".join(["", *rules]))
    first = rule_lines(checked.report, lines)[0]
    assert first["line"] == 3 and first["hint"] == "Did you mean 'electricity flows'?"


def test_two_training_objects_must_both_be_explained_by_one_set_of_rules(catalog: Catalog) -> None:
    functions = {
        "desk_lamp": {"base_with_cables": ["provide energy"], "light_bulb": ["turn energy into light"]},
        "candle": {"wax": ["provide energy"], "wick": ["turn energy into light"], "match": ["start the flame"]},
    }
    abstract = ParticipantModel("light", functions, ("provide energy AND turn energy into light CAUSES light",))
    checked = check_model(abstract, catalog, SETTINGS)
    assert checked.is_valid, checked.report.as_dict()
    assert checked.report.codes() == ["unused_function"]  # 'start the flame' of candle.match
    assert "candle.match" in checked.report.warnings[0].message
    assert model_on(abstract, "candle").object_id == "candle"
    assert model_on(abstract, "candle").labelling.functions["wick"] == ("turn energy into light",)

    rules = ("provide energy AND turn energy into light AND start the flame CAUSES light",)
    narrow = ParticipantModel("light", functions, rules)
    report = check_model(narrow, catalog, SETTINGS).report
    assert report.codes() == ["object_not_explained"]
    assert report.errors[0].message == "With the functions of the desk lamp's parts, no chain of rules produces light."


def test_limits_are_reported_as_problems_in_the_report(catalog: Catalog) -> None:
    small = Settings(database_url="sqlite://", max_rules=1)
    model = ParticipantModel("light", {"desk_lamp": DESK_LAMP}, ("a CAUSES b", "b CAUSES light"))
    checked = check_model(model, catalog, small)
    assert checked.model is None and checked.report.codes() == ["too_many_rules"]


def test_step_one_needs_a_function_and_clean_labels(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    assert check_functions(lamp, {"shade": "  \n"}, catalog, SETTINGS).codes() == ["no_functions"]
    assert check_functions(lamp, {"shade": "diffuse\x07light"}, catalog, SETTINGS).codes() == ["invalid_character"]
    assert check_functions(lamp, {"shade": "diffuse light", "light_bulb": "make light"}, catalog, SETTINGS).is_valid


def test_a_mapping_is_built_from_ticks_and_new_lines(catalog: Catalog) -> None:
    flashlight = catalog.get("flashlight")
    entries = {"head": {"chosen": ["turn electricity into light"], "added": "diffuse light\n"}, "case": {}}
    document = mapping_document(flashlight, entries)
    assert document == {"object": "flashlight", "functions": {"head": ["turn electricity into light", "diffuse light"]}}
    checked = check_mapping(document, catalog, SETTINGS)
    assert checked.is_valid and checked.mapping is not None
    empty = check_mapping(mapping_document(flashlight, {}), catalog, SETTINGS)
    assert empty.report.codes() == ["empty_mapping"]


def test_the_tutorial_example_is_valid_and_its_questions_have_answers(catalog: Catalog) -> None:
    checked = check_model(practice_model(EXAMPLE_RULES, catalog), catalog, SETTINGS)
    assert checked.is_valid
    # The functions that do not cause motion are named, as the paper's participants needed.
    assert sorted(w.message.split("'")[1] for w in checked.report.warnings) == [
        "decorate the car",
        "hold things together",
    ]
    assert wrong_answers({q.id: q.answer for q in QUESTIONS}) == []
    assert [q.id for q in wrong_answers({"sticker": "yes"})] == ["sticker", "diffuse", "and"]


def test_an_experiment_design_lists_every_problem(catalog: Catalog) -> None:
    options = {"counterbalance_training": True}
    with pytest.raises(InvalidExperimentError) as raised:
        read_design(
            " ",
            [
                {"name": "near", "training": ["desk_lamp"], "tests": ["desk_lamp", "flashlite"]},
                {"name": "NEAR ", "training": ["candle"], "tests": ["kerosene_lamp"]},
                {"name": "mixed", "training": ["toy_car"], "tests": ["candle"]},
                {"name": "three", "training": ["candle", "candle", "desk_lamp"], "tests": ["flashlight"]},
            ],
            options,
            catalog,
        )
    errors = raised.value.details["errors"]
    assert errors == [
        "The experiment's name is empty.",
        "Condition 'near': there is no object 'flashlite' in the catalog. Did you mean 'flashlight'?",
        "Condition 'near': desk_lamp cannot be both a training and a test object (tests are new).",
        "Two conditions are called 'NEAR'; give each its own name.",
        "Condition 'mixed' mixes objects with different goals: toy_car (motion), candle (light). One model "
        "explains one goal.",
        "Condition 'three' has 3 training objects; a model explains one or two.",
        "Condition 'three' lists the training object(s) candle more than once.",
    ]
    with pytest.raises(InvalidExperimentError, match="cannot be both a training and a test object"):
        read_design("x", [{"name": "a", "training": ["candle"], "tests": ["candle"]}], options, catalog)
    name, design = read_design(
        "  Near  and far ",
        [{"name": "far", "training": ["desk_lamp", "candle"], "tests": ["flashlight"]}],
        {"show_verdict": False},
        catalog,
    )
    assert name == "Near and far"
    assert design.conditions[0].training == ("desk_lamp", "candle") and not design.show_verdict


def test_the_graph_is_drawn_with_every_label_escaped(catalog: Catalog) -> None:
    functions = {"desk_lamp": {**DESK_LAMP, "shade": ["<script>alert(1)</script>"]}}
    model = ParticipantModel("light", functions, ("provide electricity AND turn electricity into light CAUSES light",))
    checked = check_model(model, catalog, SETTINGS)
    assert checked.model is not None
    svg = diagram_svg(checked.model).decode()
    assert "<script" not in svg and "&lt;script&gt;alert(1)&lt;/scr" in svg  # wrapped over two lines
    assert svg.count(">AND<") == 1 and ">light</text>" in svg and "(base with cables)" in svg


def is_valid_cookie(value: str, token: str, now: float | None = None) -> bool:
    return cookie_session(value, token, now) is not None


def test_the_sign_in_cookie_is_signed_by_the_token_and_expires() -> None:
    cookie = session_cookie("secret", now=1000.0)
    assert is_valid_cookie(cookie, "secret", now=2000.0)
    assert not is_valid_cookie(cookie, "another token", now=2000.0)
    assert not is_valid_cookie(cookie, "secret", now=1000.0 + 13 * 3600)
    assert not is_valid_cookie("99999999999." + cookie.split(".")[1], "secret", now=2000.0)
    assert not is_valid_cookie("garbage", "secret")


def test_csv_cells_that_look_like_formulas_are_defused() -> None:
    text = csv_bytes(["a", "b"], [{"a": "=HYPERLINK(1)", "b": ["x"]}]).decode()
    assert text.splitlines() == ["a,b", '\'=HYPERLINK(1),"[""x""]"']


def test_pictures_are_drawn_once_and_failures_are_not_kept() -> None:
    from causalplan.service.pages.pictures import PictureCache, drawing

    cache = PictureCache(size=2)
    calls: list[str] = []

    def draw_both() -> dict[object, bytes]:
        calls.append("both")
        return {"a": b"A", "b": b"B"}

    assert cache.get("a", draw_both) == b"A"
    assert cache.get("b", draw_both) == b"B" and calls == ["both"]  # drawn together, kept together

    def broken() -> dict[object, bytes]:
        raise RuntimeError("no simulator")

    with pytest.raises(RuntimeError):
        cache.get("c", broken)
    assert cache.get("c", lambda: {"c": b"C"}) == b"C"  # the next request tries again
    assert cache.get("a", lambda: {"a": b"new"}) == b"new"  # 'a' was the oldest of three: dropped
    assert b"&lt;b&gt;" in drawing("<b>") and b"<b>" not in drawing("<b>")
