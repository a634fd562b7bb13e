"""Reading a causal model (steps 1-2) and a step-3 mapping from plain data: shapes and their errors."""

from __future__ import annotations

from causalplan.causal.diagnostics import Diagnostic, Severity
from causalplan.causal.documents import SourceMap, parse_text
from causalplan.causal.model import (
    DEFAULT_GOAL,
    MAX_LABEL_LENGTH,
    CausalModel,
    Labelling,
    read_labelling,
    read_model,
)

DESK_LAMP = """\
object: desk_lamp
goal: light
functions:
  base_with_cables: [provide electricity]
  light_bulb: [turn electricity into light, close the circuit]
rules:
  - provide electricity AND close the circuit CAUSES electricity flows
  - electricity flows AND turn electricity into light CAUSES light
"""


def model_from(text: str) -> tuple[CausalModel | None, list[Diagnostic]]:
    data, source, problems = parse_text(text, "model.yaml")
    assert problems == [], problems
    return read_model(data, source)


def mapping_from(text: str) -> tuple[Labelling | None, list[Diagnostic]]:
    data, source, problems = parse_text(text, "mapping.yaml")
    assert problems == [], problems
    return read_labelling(data, source)


def codes(problems: list[Diagnostic]) -> list[str]:
    return [problem.code for problem in problems]


def only(problems: list[Diagnostic], code: str) -> Diagnostic:
    found = [problem for problem in problems if problem.code == code]
    assert len(found) == 1, codes(problems)
    return found[0]


# --- a good model ------------------------------------------------------------------------


def test_paper_desk_lamp_reads_without_problems() -> None:
    model, problems = model_from(DESK_LAMP)
    assert problems == []
    assert model is not None
    assert model.object_id == "desk_lamp"
    assert model.goal == "light"
    assert model.labelling.functions == {
        "base_with_cables": ("provide electricity",),
        "light_bulb": ("turn electricity into light", "close the circuit"),
    }
    assert [rule.text for rule in model.rules] == [
        "provide electricity AND close the circuit CAUSES electricity flows",
        "electricity flows AND turn electricity into light CAUSES light",
    ]
    assert [rule.index for rule in model.rules] == [1, 2]


def test_model_round_trips_to_the_file_schema() -> None:
    model, _ = model_from(DESK_LAMP)
    assert model is not None
    data = model.as_dict()
    again, problems = read_model(data, SourceMap())
    assert problems == []
    assert again == model


def test_goal_defaults_to_light() -> None:
    model, problems = model_from("object: candle\nfunctions: {wick: [burn]}\nrules: [burn CAUSES light]\n")
    assert problems == []
    assert model is not None
    assert model.goal == DEFAULT_GOAL == "light"
    assert model.goal_key == "light"


def test_goal_is_kept_as_written_and_compared_normalised() -> None:
    model, problems = model_from("object: toy_car\ngoal: '  Forward   Motion '\nfunctions: {}\nrules: []\n")
    assert problems == []
    assert model is not None
    assert model.goal == "Forward Motion"
    assert model.goal_key == "forward motion"


def test_carriers_and_labels_of_a_labelling() -> None:
    labelling, problems = mapping_from(
        "object: flashlight\nfunctions:\n  head: [Provide Electricity, diffuse light]\n"
        "  batteries: [provide  electricity]\n"
    )
    assert problems == []
    assert labelling is not None
    assert labelling.carriers() == {"diffuse light": ("head",), "provide electricity": ("batteries", "head")}
    assert labelling.labels() == {"provide electricity": "Provide Electricity", "diffuse light": "diffuse light"}


def test_used_labels_and_node_labels() -> None:
    model, _ = model_from(DESK_LAMP)
    assert model is not None
    assert model.used_labels() == {
        "light",
        "provide electricity",
        "close the circuit",
        "electricity flows",
        "turn electricity into light",
    }
    assert model.node_labels() == {
        "provide electricity": "provide electricity",
        "turn electricity into light": "turn electricity into light",
        "close the circuit": "close the circuit",
        "electricity flows": "electricity flows",
        "light": "light",
    }


def test_functions_given_as_a_single_string() -> None:
    model, problems = model_from("object: candle\nfunctions:\n  wick: burn\nrules: [burn CAUSES light]\n")
    assert problems == []
    assert model is not None
    assert model.labelling.functions == {"wick": ("burn",)}


def test_part_with_no_functions_is_an_empty_tuple() -> None:
    model, problems = model_from("object: candle\nfunctions:\n  wax:\n  wick: [burn]\nrules: [burn CAUSES light]\n")
    assert problems == []
    assert model is not None
    assert model.labelling.functions == {"wax": (), "wick": ("burn",)}


def test_rules_given_as_one_text_block_are_one_rule_per_line() -> None:
    text = "object: candle\nfunctions: {wick: [burn]}\nrules: |\n  burn CAUSES heat\n\n  heat CAUSES light\n"
    model, problems = model_from(text)
    assert problems == []
    assert model is not None
    assert [rule.text for rule in model.rules] == ["burn CAUSES heat", "heat CAUSES light"]
    assert [rule.index for rule in model.rules] == [1, 2]


def test_function_labels_have_whitespace_collapsed() -> None:
    model, _ = model_from("object: candle\nfunctions:\n  wick: ['  burn   the  wax ']\nrules: []\n")
    assert model is not None
    assert model.labelling.functions == {"wick": ("burn the wax",)}


# --- unknown and missing fields -------------------------------------------------------------


def test_unknown_field_rule_suggests_rules() -> None:
    _, problems = model_from("object: desk_lamp\nfunctions: {}\nrule:\n  - a CAUSES light\n")
    problem = only(problems, "unknown_field")
    assert problem.severity is Severity.ERROR
    assert "'rule'" in problem.message
    assert problem.hint == "Did you mean 'rules'?"
    assert problem.location.line == 3
    assert problem.location.file == "model.yaml"


def test_unknown_field_functoins_suggests_functions() -> None:
    _, problems = model_from("object: desk_lamp\nfunctoins: {}\nrules: []\n")
    assert only(problems, "unknown_field").hint == "Did you mean 'functions'?"


def test_unknown_field_without_a_close_match_lists_the_fields() -> None:
    _, problems = model_from("object: desk_lamp\nfunctions: {}\nrules: []\ncolour: red\n")
    hint = only(problems, "unknown_field").hint
    assert hint is not None
    assert "object, goal, functions, rules" in hint


def test_missing_fields_each_name_the_field() -> None:
    _, problems = model_from("goal: light\n")
    missing = [p for p in problems if p.code == "missing_field"]
    assert [p.message for p in missing] == [
        "The model has no 'object' field.",
        "The model has no 'functions' field.",
        "The model has no 'rules' field.",
    ]
    assert all(p.hint for p in missing)


def test_missing_rules_still_gives_a_model() -> None:
    model, problems = model_from("object: desk_lamp\nfunctions: {shade: [diffuse light]}\n")
    assert codes(problems) == ["missing_field"]
    assert model is not None
    assert model.rules == ()


def test_rules_in_a_mapping_is_a_clear_error() -> None:
    labelling, problems = mapping_from("object: flashlight\nfunctions:\n  case: [a]\nrules:\n  - a CAUSES light\n")
    assert labelling is not None
    problem = only(problems, "unknown_field")
    assert "'rules'" in problem.message
    assert problem.hint == "A step-3 mapping cannot change the rules: the training model stays as it was."
    assert problem.location.line == 4


def test_goal_in_a_mapping_is_an_unknown_field() -> None:
    _, problems = mapping_from("object: flashlight\nfunctions: {}\ngoal: light\n")
    problem = only(problems, "unknown_field")
    assert problem.hint == "A mapping has the fields: object, functions."


def test_mapping_missing_functions() -> None:
    _, problems = mapping_from("object: flashlight\n")
    assert codes(problems) == ["missing_field"]
    assert "'functions'" in problems[0].message


def test_mapping_missing_object() -> None:
    labelling, problems = mapping_from("functions: {head: [provide electricity]}\n")
    assert codes(problems) == ["missing_field"]
    assert labelling is not None
    assert labelling.object_id == ""


def test_paper_flashlight_mapping_reads() -> None:
    labelling, problems = mapping_from(
        "object: flashlight\nfunctions:\n  batteries: [provide electricity]\n"
        "  head: [turn electricity into light, close the circuit]\n"
    )
    assert problems == []
    assert labelling is not None
    assert labelling.object_id == "flashlight"
    assert labelling.as_dict() == {
        "object": "flashlight",
        "functions": {
            "batteries": ["provide electricity"],
            "head": ["turn electricity into light", "close the circuit"],
        },
    }


# --- wrong shapes -------------------------------------------------------------------------------


def test_model_that_is_not_a_mapping() -> None:
    for data in (None, [], "desk_lamp", 3):
        model, problems = read_model(data, SourceMap("model.yaml"))
        assert model is None
        assert codes(problems) == ["invalid_type"], data


def test_mapping_that_is_not_a_mapping() -> None:
    labelling, problems = read_labelling(["object", "functions"], SourceMap("mapping.yaml"))
    assert labelling is None
    assert codes(problems) == ["invalid_type"]


def test_object_that_is_not_text() -> None:
    _, problems = model_from("object: 12\nfunctions: {}\nrules: []\n")
    problem = only(problems, "invalid_type")
    assert "'object'" in problem.message
    assert problem.location.line == 1


def test_blank_object_is_invalid_type() -> None:
    _, problems = model_from("object: '  '\nfunctions: {}\nrules: []\n")
    assert codes(problems) == ["invalid_type"]


def test_functions_that_are_a_list() -> None:
    _, problems = model_from("object: desk_lamp\nfunctions: [provide electricity]\nrules: []\n")
    problem = only(problems, "invalid_type")
    assert "'functions'" in problem.message
    assert problem.location.line == 2


def test_functions_of_a_part_that_are_a_mapping() -> None:
    _, problems = model_from("object: desk_lamp\nfunctions:\n  shade: {diffuse: light}\nrules: []\n")
    problem = only(problems, "invalid_type")
    assert problem.location.part == "shade"
    assert problem.location.line == 3


def test_non_text_function_labels_are_invalid_type() -> None:
    text = "object: desk_lamp\nfunctions:\n  shade:\n    - diffuse light\n    - 42\n    - [nested]\nrules: []\n"
    model, problems = model_from(text)
    assert codes(problems) == ["invalid_type", "invalid_type"]
    assert [p.location.line for p in problems] == [5, 6]
    assert "int" in problems[0].message and "list" in problems[1].message
    assert all(p.location.part == "shade" for p in problems)
    assert model is not None
    assert model.labelling.functions == {"shade": ("diffuse light",)}


def test_yaml_boolean_words_as_labels_are_invalid_type() -> None:
    # YAML reads an unquoted 'yes' as true: the person must quote it.
    _, problems = model_from("object: desk_lamp\nfunctions:\n  shade: [yes]\nrules: []\n")
    assert codes(problems) == ["invalid_type"]
    assert "bool" in problems[0].message


def test_empty_function_label() -> None:
    _, problems = model_from("object: desk_lamp\nfunctions:\n  shade: ['  ']\nrules: []\n")
    assert codes(problems) == ["empty_label"]
    assert problems[0].location.part == "shade"


def test_function_label_with_control_character() -> None:
    _, problems = model_from('object: desk_lamp\nfunctions:\n  shade: ["dif\\u200bfuse"]\nrules: []\n')
    assert codes(problems) == ["invalid_character"]


def test_label_too_long() -> None:
    label = "x" * (MAX_LABEL_LENGTH + 1)
    _, problems = model_from(f"object: desk_lamp\nfunctions:\n  shade:\n    - {label}\nrules: []\n")
    problem = only(problems, "label_too_long")
    assert str(MAX_LABEL_LENGTH + 1) in problem.message
    assert problem.location.line == 4


def test_label_at_the_length_limit_is_accepted() -> None:
    label = "x" * MAX_LABEL_LENGTH
    model, problems = model_from(f"object: desk_lamp\nfunctions:\n  shade: [{label}]\nrules: []\n")
    assert problems == []
    assert model is not None
    assert model.labelling.functions["shade"] == (label,)


def test_duplicate_function_warns_with_its_line() -> None:
    text = (
        "object: desk_lamp\nfunctions:\n  light_bulb:\n    - close the circuit\n    - Close  The Circuit\nrules: []\n"
    )
    model, problems = model_from(text)
    problem = only(problems, "duplicate_function")
    assert problem.severity is Severity.WARNING
    assert problem.location.line == 5
    assert problem.location.part == "light_bulb"
    assert model is not None
    assert model.labelling.functions == {"light_bulb": ("close the circuit",)}


def test_same_function_on_two_parts_is_not_a_duplicate() -> None:
    _, problems = mapping_from(
        "object: flashlight\nfunctions:\n  head: [provide electricity]\n  batteries: [provide electricity]\n"
    )
    assert problems == []


def test_rules_that_are_a_mapping_are_invalid_type() -> None:
    _, problems = model_from("object: desk_lamp\nfunctions: {}\nrules:\n  light: provide electricity\n")
    problem = only(problems, "invalid_type")
    assert "'rules'" in problem.message
    assert problem.location.line == 3


def test_non_text_rule_is_invalid_type_with_rule_index() -> None:
    text = "object: desk_lamp\nfunctions: {}\nrules:\n  - a CAUSES light\n  - 7\n  - {a: b}\n"
    model, problems = model_from(text)
    assert codes(problems) == ["invalid_type", "invalid_type"]
    assert [(p.location.rule, p.location.line) for p in problems] == [(2, 5), (3, 6)]
    assert model is not None
    assert [rule.index for rule in model.rules] == [1]


def test_rule_syntax_errors_carry_rule_index_and_line() -> None:
    text = "object: desk_lamp\nfunctions: {}\nrules:\n  - a CAUSES light\n  - b light\n"
    model, problems = model_from(text)
    problem = only(problems, "missing_causes_keyword")
    assert (problem.location.rule, problem.location.line, problem.location.file) == (2, 5, "model.yaml")
    assert model is not None
    assert len(model.rules) == 1


def test_overlong_rule_is_label_too_long() -> None:
    rule = " AND ".join(["provide electricity"] * 40) + " CAUSES light"
    _, problems = model_from(f"object: desk_lamp\nfunctions: {{}}\nrules:\n  - {rule}\n")
    problem = only(problems, "label_too_long")
    assert problem.location.rule == 1


def test_empty_goal_is_empty_label() -> None:
    model, problems = model_from("object: desk_lamp\ngoal: ''\nfunctions: {}\nrules: []\n")
    assert codes(problems) == ["empty_label"]
    assert problems[0].location.line == 2
    assert model is not None
    assert model.goal == DEFAULT_GOAL


def test_goal_that_is_not_text_is_invalid_type() -> None:
    _, problems = model_from("object: desk_lamp\ngoal: 7\nfunctions: {}\nrules: []\n")
    assert codes(problems) == ["invalid_type"]


def test_goal_with_control_character_is_invalid_character() -> None:
    _, problems = model_from('object: desk_lamp\ngoal: "li\\u0000ght"\nfunctions: {}\nrules: []\n')
    assert codes(problems) == ["invalid_character"]


def test_overlong_goal_is_label_too_long() -> None:
    goal = "x" * (MAX_LABEL_LENGTH + 1)
    _, problems = model_from(f"object: desk_lamp\ngoal: {goal}\nfunctions: {{}}\nrules: []\n")
    assert codes(problems) == ["label_too_long"]


def test_numeric_part_ids_become_text() -> None:
    model, problems = model_from("object: desk_lamp\nfunctions:\n  1: [a]\nrules: []\n")
    assert problems == []
    assert model is not None
    assert model.labelling.functions == {"1": ("a",)}


def test_an_empty_object_is_an_error_not_a_crash_later() -> None:
    for text in ("object:\nfunctions: {}\nrules: []\n", '{"object": null, "functions": {}, "rules": []}'):
        _, problems = model_from(text)
        assert only(problems, "invalid_type").location.line == 1
