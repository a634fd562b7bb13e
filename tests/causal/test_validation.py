"""Checks of a causal model's meaning: each code, with the place it points at and the hint it gives."""

from __future__ import annotations

import unicodedata

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from causalplan.causal.diagnostics import Diagnostic, Report, Severity
from causalplan.causal.documents import SourceMap
from causalplan.causal.model import read_labelling, read_model
from causalplan.causal.validation import ObjectSummary, validate_mapping, validate_model
from causalplan.inputs import load_mapping, load_model, model_from_data, model_from_text
from causalplan.objects.catalog import load_catalog
from tests.conftest import EXAMPLES, builtin_catalog


def report_of(text: str) -> Report:
    loaded = model_from_text(text, builtin_catalog(), "model.yaml")
    assert loaded.model is not None, loaded.report.codes()
    return loaded.report


def only(report: Report, code: str) -> Diagnostic:
    found = [d for d in report.diagnostics if d.code == code]
    assert len(found) == 1, report.codes()
    return found[0]


DESK_LAMP_HEAD = """\
object: desk_lamp
goal: light
functions:
  base_with_cables: [provide electricity]
  light_bulb: [turn electricity into light, close the circuit]
rules:
"""


def desk_lamp_with(*rules: str) -> str:
    """Return the paper's desk-lamp labelling with these rules (rule 1 is on line 7)."""
    return DESK_LAMP_HEAD + "".join(f"  - {rule}\n" for rule in rules)


# --- the paper's examples ---------------------------------------------------------------------


def test_paper_desk_lamp_is_valid_without_warnings() -> None:
    loaded = load_model(EXAMPLES / "paper" / "desk_lamp.yaml", builtin_catalog())
    assert loaded.is_valid
    assert loaded.report.diagnostics == ()


def test_paper_failed_desk_lamp_is_a_valid_model() -> None:
    # The paper: "participants created valid causal models ... but their model failed to transfer".
    loaded = load_model(EXAMPLES / "paper" / "failed_desk_lamp.yaml", builtin_catalog())
    assert loaded.is_valid
    assert loaded.report.diagnostics == ()


def test_every_example_model_is_valid() -> None:
    models = [
        EXAMPLES / "paper" / "desk_lamp.yaml",
        EXAMPLES / "paper" / "failed_desk_lamp.yaml",
        EXAMPLES / "far" / "abstract_desk_lamp.yaml",
        EXAMPLES / "near" / "candle.yaml",
    ]
    for path in models:
        loaded = load_model(path, builtin_catalog())
        assert loaded.is_valid, (path, loaded.report.codes())


def test_every_example_mapping_of_a_builtin_object_is_valid() -> None:
    mappings = [
        EXAMPLES / "paper" / "flashlight_mapping.yaml",
        EXAMPLES / "paper" / "failed_flashlight_mapping.yaml",
        EXAMPLES / "far" / "candle_mapping.yaml",
        EXAMPLES / "far" / "candle_mapping_for_paper_desk_lamp.yaml",
        EXAMPLES / "far" / "flashlight_mapping_for_candle.yaml",
        EXAMPLES / "near" / "kerosene_lamp_mapping.yaml",
    ]
    for path in mappings:
        loaded = load_mapping(path, builtin_catalog())
        assert loaded.is_valid, (path, loaded.report.codes())


def test_user_mapping_is_valid_only_with_its_catalog() -> None:
    path = EXAMPLES / "user" / "bedside_lamp_mapping.yaml"
    assert load_mapping(path, builtin_catalog()).report.codes() == ["unknown_object"]
    assert load_mapping(path, load_catalog([EXAMPLES / "catalog"])).is_valid


# --- object and parts ---------------------------------------------------------------------------


def test_unknown_object_suggests_the_close_one() -> None:
    report = report_of("object: desk_lmap\nfunctions: {}\nrules: [a CAUSES light]\n")
    problem = only(report, "unknown_object")
    assert problem.severity is Severity.ERROR
    assert "'desk_lmap'" in problem.message
    assert problem.hint == "Did you mean 'desk_lamp'?"
    assert problem.location.line == 1


def test_unknown_object_without_a_close_one_lists_the_catalog() -> None:
    report = report_of("object: spaceship\nfunctions: {}\nrules: [a CAUSES light]\n")
    hint = only(report, "unknown_object").hint
    assert hint is not None
    for object_id in ("candle", "desk_lamp", "flashlight", "kerosene_lamp", "toy_car"):
        assert object_id in hint


def test_unknown_part_suggests_base_with_cables() -> None:
    text = (
        "object: desk_lamp\nfunctions:\n  base_with_cable: [provide electricity]\n"
        "rules: [provide electricity CAUSES light]\n"
    )
    problem = only(report_of(text), "unknown_part")
    assert problem.severity is Severity.ERROR
    assert "'base_with_cable'" in problem.message
    assert problem.hint == "Did you mean 'base_with_cables'?"
    assert problem.location.line == 3
    assert problem.location.part == "base_with_cable"


def test_unknown_part_without_a_close_one_lists_the_parts() -> None:
    text = (
        "object: desk_lamp\nfunctions:\n  battery_pack: [provide electricity]\n"
        "rules: [provide electricity CAUSES light]\n"
    )
    hint = only(report_of(text), "unknown_part").hint
    assert hint == "Its parts are: base_with_cables, light_bulb, shade."


def test_unknown_part_in_a_mapping() -> None:
    data = {"object": "flashlight", "functions": {"bateries": ["provide electricity"]}}
    labelling, problems = read_labelling(data, SourceMap())
    assert labelling is not None
    report = validate_mapping(labelling, builtin_catalog().summaries(), problems)
    assert report.codes() == ["unknown_part"]
    assert report.diagnostics[0].hint == "Did you mean 'batteries'?"


def test_mapping_keeps_earlier_problems_first() -> None:
    data = {"object": "flashlight", "functions": {"head": [7]}}
    labelling, problems = read_labelling(data, SourceMap())
    assert labelling is not None
    assert validate_mapping(labelling, builtin_catalog().summaries(), problems).codes() == ["invalid_type"]


# --- causes -------------------------------------------------------------------------------------


def test_uncaused_effect_is_the_papers_invalid_model() -> None:
    # The paper: "some users specified intermediate effect nodes ... but did not specify their causes".
    report = report_of(
        desk_lamp_with(
            "provide electricity AND close the circuit CAUSES electricity flows",
            "current AND turn electricity into light CAUSES light",
        )
    )
    assert not report.is_valid
    problem = only(report, "uncaused_effect")
    assert "'current'" in problem.message
    assert (problem.location.rule, problem.location.line) == (2, 8)
    assert problem.hint is not None
    assert "add a rule that causes it" in problem.hint
    assert "CAUSES current" in problem.hint


def test_uncaused_effect_is_reported_once_per_label() -> None:
    report = report_of(
        desk_lamp_with(
            "magic CAUSES electricity flows",
            "Magic AND turn electricity into light CAUSES light",
        )
    )
    assert report.codes().count("uncaused_effect") == 1


def test_unknown_cause_is_a_typo_with_did_you_mean() -> None:
    report = report_of(
        desk_lamp_with(
            "provide electricty AND close the circuit CAUSES electricity flows",
            "electricity flows AND turn electricity into light CAUSES light",
        )
    )
    problem = only(report, "unknown_cause")
    assert problem.severity is Severity.ERROR
    assert "'provide electricty'" in problem.message
    assert problem.hint == "Did you mean 'provide electricity'?"
    assert (problem.location.rule, problem.location.line) == (1, 7)


def test_unknown_cause_suggests_an_intermediate_effect_too() -> None:
    report = report_of(
        desk_lamp_with(
            "provide electricity AND close the circuit CAUSES electricity flows",
            "electricity flow AND turn electricity into light CAUSES light",
        )
    )
    assert only(report, "unknown_cause").hint == "Did you mean 'electricity flows'?"


def test_cause_matching_a_function_in_other_case_and_spacing_is_known() -> None:
    report = report_of(
        desk_lamp_with(
            "Provide  ELECTRICITY AND close the circuit CAUSES electricity flows",
            "electricity flows AND Turn Electricity Into Light CAUSES Light",
        )
    )
    assert report.diagnostics == ()


def test_cause_with_different_punctuation_is_not_the_function() -> None:
    report = report_of(
        desk_lamp_with(
            "provide-electricity AND close the circuit CAUSES electricity flows",
            "electricity flows AND turn electricity into light CAUSES light",
        )
    )
    assert "unknown_cause" in report.codes()
    assert not report.is_valid


# --- goal ---------------------------------------------------------------------------------------


def test_goal_not_produced() -> None:
    report = report_of(desk_lamp_with("provide electricity AND close the circuit CAUSES electricity flows"))
    problem = only(report, "goal_not_produced")
    assert problem.severity is Severity.ERROR
    assert "'light'" in problem.message
    assert problem.location.line == 6  # the 'rules' field
    assert problem.hint is not None and "CAUSES light" in problem.hint


def test_goal_not_produced_when_there_are_no_rules() -> None:
    report = report_of(DESK_LAMP_HEAD.replace("rules:\n", "rules: []\n"))
    assert "goal_not_produced" in report.codes()


def test_goal_is_matched_after_normalisation() -> None:
    text = desk_lamp_with("provide electricity AND close the circuit AND turn electricity into light CAUSES LIGHT")
    assert report_of(text).is_valid


def test_goal_differs_from_object() -> None:
    text = (
        "object: toy_car\ngoal: light\nfunctions:\n  wind_up_motor: [store energy]\n"
        "rules:\n  - store energy CAUSES light\n"
    )
    report = report_of(text)
    problem = only(report, "goal_differs_from_object")
    assert problem.severity is Severity.WARNING
    assert "'motion'" in problem.message
    assert problem.location.line == 2
    assert problem.hint == "Set 'goal: motion' unless you mean something else."
    assert report.is_valid


def test_default_goal_on_toy_car_differs_from_object() -> None:
    text = "object: toy_car\nfunctions:\n  wind_up_motor: [store energy]\nrules:\n  - store energy CAUSES light\n"
    assert "goal_differs_from_object" in report_of(text).codes()


def test_toy_car_with_goal_motion_is_clean() -> None:
    text = (
        "object: toy_car\ngoal: motion\nfunctions:\n  wind_up_motor: [store energy]\n  wheels: [roll]\n"
        "rules:\n  - store energy AND roll CAUSES motion\n"
    )
    assert report_of(text).diagnostics == ()


# --- cycles -------------------------------------------------------------------------------------


def test_cycle_is_named_with_arrows() -> None:
    report = report_of(
        desk_lamp_with(
            "provide electricity AND heat CAUSES glow",
            "glow CAUSES heat",
            "glow AND turn electricity into light CAUSES light",
        )
    )
    problem = only(report, "cycle")
    assert problem.severity is Severity.ERROR
    assert problem.message in (
        "The rules go round in a circle: glow → heat → glow.",
        "The rules go round in a circle: heat → glow → heat.",
    )
    assert problem.location.rule == 1
    assert problem.location.line == 7
    assert problem.hint is not None and "rules 1, 2" in problem.hint


def test_rule_that_causes_its_own_cause_is_a_cycle() -> None:
    report = report_of(desk_lamp_with("provide electricity AND light CAUSES light"))
    problem = only(report, "cycle")
    assert "light → light" in problem.message


def test_three_rule_cycle_names_every_node() -> None:
    report = report_of(
        desk_lamp_with(
            "a CAUSES b",
            "b CAUSES c",
            "c AND provide electricity CAUSES a",
            "a AND turn electricity into light CAUSES light",
        )
    )
    message = only(report, "cycle").message
    for label in ("a", "b", "c"):
        assert f"{label} →" in message
    assert message.count("→") == 3


def test_a_diamond_is_not_a_cycle() -> None:
    report = report_of(
        desk_lamp_with(
            "provide electricity CAUSES power",
            "power CAUSES heat",
            "power CAUSES glow",
            "heat AND glow AND turn electricity into light CAUSES light",
        )
    )
    assert "cycle" not in report.codes()
    assert report.is_valid


# --- warnings -----------------------------------------------------------------------------------


def test_duplicate_rule_is_a_warning_pointing_at_the_second() -> None:
    report = report_of(
        desk_lamp_with(
            "provide electricity AND close the circuit AND turn electricity into light CAUSES light",
            "Turn electricity into light and close the circuit and provide  electricity causes Light",
        )
    )
    problem = only(report, "duplicate_rule")
    assert problem.severity is Severity.WARNING
    assert problem.message == "Rule 2 says the same as rule 1."
    assert (problem.location.rule, problem.location.line) == (2, 8)
    assert report.is_valid


def test_same_effect_with_other_causes_is_not_a_duplicate() -> None:
    report = report_of(
        desk_lamp_with(
            "provide electricity AND close the circuit AND turn electricity into light CAUSES light",
            "provide electricity AND turn electricity into light CAUSES light",
        )
    )
    assert "duplicate_rule" not in report.codes()


def test_unused_function_is_the_papers_diffuse_light() -> None:
    text = (
        "object: desk_lamp\ngoal: light\nfunctions:\n  shade: [diffuse light]\n"
        "  light_bulb: [turn electricity into light]\n  base_with_cables: [provide electricity]\n"
        "rules:\n  - provide electricity AND turn electricity into light CAUSES light\n"
    )
    report = report_of(text)
    problem = only(report, "unused_function")
    assert problem.severity is Severity.WARNING
    assert "'diffuse light'" in problem.message and "shade" in problem.message
    assert problem.location.part == "shade"
    assert problem.location.line == 4
    assert report.is_valid


def test_unused_function_is_reported_once_for_several_parts() -> None:
    data = {
        "object": "flashlight",
        "functions": {"head": ["provide electricity", "glow"], "batteries": ["provide electricity"], "case": ["Glow"]},
        "rules": ["provide electricity CAUSES light"],
    }
    report = model_from_data(data, SourceMap(), builtin_catalog()).report
    problem = only(report, "unused_function")
    assert "case, head" in problem.message


def test_unused_effect() -> None:
    report = report_of(
        desk_lamp_with(
            "provide electricity AND close the circuit CAUSES heat",
            "provide electricity AND close the circuit AND turn electricity into light CAUSES light",
        )
    )
    problem = only(report, "unused_effect")
    assert problem.severity is Severity.WARNING
    assert "'heat'" in problem.message
    assert (problem.location.rule, problem.location.line) == (1, 7)
    assert report.is_valid


def test_effect_is_function() -> None:
    report = report_of(
        desk_lamp_with(
            "provide electricity CAUSES close the circuit",
            "close the circuit AND turn electricity into light CAUSES light",
        )
    )
    problem = only(report, "effect_is_function")
    assert problem.severity is Severity.WARNING
    assert "'close the circuit'" in problem.message
    assert problem.location.part == "light_bulb"
    assert problem.location.line == 5
    assert report.is_valid


def test_warnings_leave_a_model_valid_and_errors_do_not() -> None:
    warned = report_of(
        desk_lamp_with(
            "provide electricity AND close the circuit AND turn electricity into light CAUSES light",
            "provide electricity AND close the circuit CAUSES heat",
        )
    )
    assert warned.is_valid and warned.warnings and not warned.errors
    failed = report_of(desk_lamp_with("nothing at all CAUSES light"))
    assert not failed.is_valid


def test_earlier_reading_problems_come_first() -> None:
    report = report_of(desk_lamp_with("provide electricity light", "provide electricity CAUSES glow"))
    assert report.codes()[0] == "missing_causes_keyword"
    assert "goal_not_produced" in report.codes()


def test_report_as_dict_shape() -> None:
    report = report_of(desk_lamp_with("current AND turn electricity into light CAUSES light"))
    data = report.as_dict()
    assert data["valid"] is False
    errors = data["errors"]
    assert isinstance(errors, list) and errors
    first = errors[0]
    assert set(first) == {"code", "severity", "message", "location", "hint"}
    assert first["location"] == {"file": "model.yaml", "line": 7, "rule": 1}


# --- properties -----------------------------------------------------------------------------------

KEYWORDS = {"and", "causes", "or"}
OBJECT_PARTS = {obj_id: list(summary.part_ids) for obj_id, summary in builtin_catalog().summaries().items()}

words = st.text(alphabet="abcdefghijklmnopqrstuvwxyzéü-'!", min_size=1, max_size=7).filter(
    lambda word: word.casefold() not in KEYWORDS
)
labels = st.lists(words, min_size=1, max_size=3).map(" ".join)
rule_pieces = st.one_of(
    words, st.sampled_from(["AND", "and", "CAUSES", "causes", "OR", " ", "\t", "", "light"]), st.text(max_size=8)
)
arbitrary_rules = st.lists(rule_pieces, max_size=12).map(" ".join)
arbitrary_labels = st.one_of(
    st.text(max_size=30), labels, st.integers(), st.none(), st.booleans(), st.lists(st.text(max_size=5), max_size=2)
)


@st.composite
def arbitrary_documents(draw: st.DrawFn) -> dict[str, object]:
    parts = st.one_of(
        st.sampled_from(["shade", "light_bulb", "base_with_cables", "head", "wick"]), st.text(max_size=10)
    )
    document: dict[str, object] = {
        "object": draw(st.one_of(st.sampled_from(sorted(OBJECT_PARTS)), st.text(max_size=10), st.integers())),
        "functions": draw(
            st.one_of(
                st.dictionaries(parts, st.one_of(arbitrary_labels, st.lists(arbitrary_labels, max_size=4)), max_size=4),
                arbitrary_labels,
            )
        ),
        "rules": draw(st.one_of(st.lists(st.one_of(arbitrary_rules, arbitrary_labels), max_size=6), arbitrary_rules)),
    }
    if draw(st.booleans()):
        document["goal"] = draw(st.one_of(st.just("light"), labels, arbitrary_labels))
    if draw(st.booleans()):
        document[draw(st.text(max_size=8))] = draw(arbitrary_labels)
    return document


@pytest.mark.slow
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(arbitrary_documents())
def test_validate_never_raises_on_arbitrary_input(document: dict[str, object]) -> None:
    loaded = model_from_data(document, SourceMap(), builtin_catalog())
    assert loaded.model is not None
    data = loaded.report.as_dict()
    assert data["valid"] is loaded.report.is_valid
    for diagnostic in loaded.report.diagnostics:
        assert diagnostic.code and diagnostic.message


def vary(label: str, upper: bool, spaces: int) -> str:
    """Return the same label as a person might retype it: other case, more spaces."""
    text = label.upper() if upper else label
    return (" " * spaces).join(text.split()).join(["  ", " "])


@st.composite
def valid_models(draw: st.DrawFn) -> dict[str, object]:
    """Return a model valid by construction: every cause is a function or an earlier effect."""
    object_id = draw(st.sampled_from(["desk_lamp", "flashlight", "candle", "kerosene_lamp"]))
    parts = OBJECT_PARTS[object_id]
    distinct = st.lists(labels, min_size=2, max_size=7, unique_by=lambda label: " ".join(label.split()).casefold())
    names = [name for name in draw(distinct) if " ".join(name.split()).casefold() != "light"]
    split = draw(st.integers(min_value=1, max_value=max(1, len(names))))
    functions, effects = names[:split], names[split:]
    carried: dict[str, list[str]] = {}
    for function in functions:
        carried.setdefault(draw(st.sampled_from(parts)), []).append(function)
    rules: list[str] = []
    for position, effect in enumerate([*effects, "light"]):
        available = functions + effects[:position]
        causes = draw(st.lists(st.sampled_from(available), min_size=1, max_size=3))
        written = [vary(cause, draw(st.booleans()), draw(st.integers(1, 3))) for cause in causes]
        keyword_and = draw(st.sampled_from([" AND ", " and ", "  And\t"]))
        keyword_causes = draw(st.sampled_from([" CAUSES ", " causes ", "\tCauses  "]))
        rules.append(keyword_and.join(written) + keyword_causes + effect)
    return {"object": object_id, "goal": "light", "functions": carried, "rules": rules}


@pytest.mark.slow
@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(valid_models())
def test_model_valid_by_construction_has_no_errors(document: dict[str, object]) -> None:
    model, problems = read_model(document, SourceMap())
    assert model is not None
    report = validate_model(model, builtin_catalog().summaries(), problems)
    assert report.errors == [], (document, report.codes())


def test_objects_summary_drives_validation() -> None:
    summaries = {"lamp": ObjectSummary("lamp", ("base", "bulb"), "light")}
    data = {"object": "lamp", "functions": {"bulb": ["glow"]}, "rules": ["glow CAUSES light"]}
    model, problems = read_model(data, SourceMap())
    assert model is not None
    assert validate_model(model, summaries, problems).diagnostics == ()


def test_a_rule_causing_itself_names_that_one_rule() -> None:
    looped, problems = read_model(
        {
            "object": "desk_lamp",
            "functions": {"light_bulb": ["glow"]},
            "rules": ["glow CAUSES light", "light AND glow CAUSES light"],
        },
        SourceMap(),
    )
    assert looped is not None
    cycles = [d for d in validate_model(looped, builtin_catalog().summaries(), problems).errors if d.code == "cycle"]
    assert len(cycles) == 1
    assert cycles[0].message == "The rules go round in a circle: light → light."
    assert cycles[0].hint is not None and cycles[0].hint.endswith("Remove or change rule 2.")


# --- labels people cannot tell apart, or cannot use -----------------------------------------------


def test_a_function_written_composed_is_used_by_a_rule_written_decomposed() -> None:
    composed, decomposed = unicodedata.normalize("NFC", "café power"), unicodedata.normalize("NFD", "café power")
    text = DESK_LAMP_HEAD.replace("provide electricity", composed) + (
        f"  - {decomposed} AND close the circuit AND turn electricity into light CAUSES light\n"
    )
    report = report_of(text)
    assert report.is_valid, report.codes()
    assert "unused_function" not in report.codes()


def test_a_function_holding_a_keyword_is_warned_about() -> None:
    text = DESK_LAMP_HEAD.replace("[provide electricity]", "[provide electricity, rock and roll]") + (
        "  - provide electricity AND close the circuit AND turn electricity into light CAUSES light\n"
    )
    problem = only(report_of(text), "keyword_in_label")
    assert problem.severity is Severity.WARNING
    assert "'rock and roll'" in problem.message and "AND" in problem.message
    assert problem.location.part == "base_with_cables"
    assert problem.location.line == 4


def test_a_function_holding_causes_is_warned_about_too() -> None:
    mapping = {"object": "desk_lamp", "functions": {"light_bulb": ["heat causes light"]}}
    labelling, problems = read_labelling(mapping, SourceMap())
    assert labelling is not None
    assert [p.code for p in problems] == ["keyword_in_label"]
    assert "CAUSES" in problems[0].message


def test_words_that_only_contain_a_keyword_are_not_warned_about() -> None:
    mapping = {"object": "desk_lamp", "functions": {"light_bulb": ["hand over power", "rock-and-roll"]}}
    _, problems = read_labelling(mapping, SourceMap())
    assert problems == []


def test_the_missing_goal_hint_suggests_the_form_not_a_label() -> None:
    # The toy car of the tutorial: its first function is the one it teaches to leave out.
    text = (
        "object: toy_car\ngoal: motion\nfunctions:\n  chassis: [hold things together]\n"
        "  wind_up_motor: [store energy]\nrules:\n  - store energy CAUSES stored motion\n"
    )
    loaded = model_from_text(text, builtin_catalog(), "model.yaml")
    assert loaded.model is not None
    problem = only(loaded.report, "goal_not_produced")
    assert problem.hint is not None
    assert "hold things together" not in problem.hint
    assert "FUNCTION AND FUNCTION CAUSES motion" in problem.hint
