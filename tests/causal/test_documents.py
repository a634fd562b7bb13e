"""Reading YAML/JSON documents with the line of every value; problems are diagnostics, never raised."""

from __future__ import annotations

from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from causalplan.causal.documents import MAX_DOCUMENT_BYTES, SourceMap, parse_text, read_document

MODEL_YAML = """\
# the paper's desk lamp
object: desk_lamp
goal: light
functions:
  shade: [diffuse light]
  light_bulb:
    - turn electricity into light
    - close the circuit
rules:
  - provide electricity AND close the circuit CAUSES electricity flows
  - electricity flows AND turn electricity into light CAUSES light
"""

MODEL_JSON = """\
{
  "object": "desk_lamp",
  "functions": {
    "light_bulb": ["turn electricity into light",
                   "close the circuit"]
  },
  "rules": [
    "provide electricity AND close the circuit CAUSES electricity flows",
    "electricity flows AND turn electricity into light CAUSES light"
  ]
}
"""


# --- parsing and line numbers ---------------------------------------------------------------


def test_yaml_parses_to_plain_data() -> None:
    data, _, problems = parse_text(MODEL_YAML, "model.yaml")
    assert problems == []
    assert data == {
        "object": "desk_lamp",
        "goal": "light",
        "functions": {"shade": ["diffuse light"], "light_bulb": ["turn electricity into light", "close the circuit"]},
        "rules": [
            "provide electricity AND close the circuit CAUSES electricity flows",
            "electricity flows AND turn electricity into light CAUSES light",
        ],
    }


def test_yaml_lines_of_fields_parts_labels_and_rules() -> None:
    _, source, _ = parse_text(MODEL_YAML, "model.yaml")
    assert source.file == "model.yaml"
    assert source.locate("object").line == 2
    assert source.locate("goal").line == 3
    assert source.locate("functions").line == 4
    assert source.locate("functions", "shade").line == 5
    assert source.locate("functions", "shade", 0).line == 5
    assert source.locate("functions", "light_bulb").line == 6
    assert source.locate("functions", "light_bulb", 0).line == 7
    assert source.locate("functions", "light_bulb", 1).line == 8
    assert source.locate("rules").line == 9
    assert source.locate("rules", 0).line == 10
    assert source.locate("rules", 1).line == 11


def test_locate_of_the_whole_document_is_its_first_value() -> None:
    _, source, _ = parse_text(MODEL_YAML, "model.yaml")
    assert source.locate().line == 2  # line 1 is a comment


def test_locate_falls_back_to_the_nearest_located_parent() -> None:
    _, source, _ = parse_text(MODEL_YAML, "model.yaml")
    assert source.locate("functions", "head", 3).line == 4
    assert source.locate("rules", 9).line == 9
    assert source.locate("nonsense").line == 2


def test_locate_passes_rule_part_and_file_through() -> None:
    _, source, _ = parse_text(MODEL_YAML, "model.yaml")
    where = source.locate("rules", 1, rule=2)
    assert (where.file, where.line, where.rule, where.part) == ("model.yaml", 11, 2, None)
    where = source.locate("functions", "shade", part="shade")
    assert (where.line, where.part) == (5, "shade")


def test_empty_source_map_locates_nothing() -> None:
    where = SourceMap("x.yaml").locate("rules", 0, rule=1)
    assert where.file == "x.yaml"
    assert where.line is None
    assert where.rule == 1


def test_json_parses_with_lines() -> None:
    data, source, problems = parse_text(MODEL_JSON, "model.json")
    assert problems == []
    assert isinstance(data, dict)
    assert data["object"] == "desk_lamp"
    assert source.locate("object").line == 2
    assert source.locate("functions", "light_bulb").line == 4
    assert source.locate("functions", "light_bulb", 1).line == 5
    assert source.locate("rules", 0).line == 8
    assert source.locate("rules", 1).line == 9


def test_json_is_recognised_without_a_file_name() -> None:
    data, _, problems = parse_text('{"object": "candle"}')
    assert problems == []
    assert data == {"object": "candle"}


def test_json_indented_with_tabs_still_has_lines() -> None:
    text = '{\n\t"object": "desk_lamp",\n\t"rules": [\n\t\t"a CAUSES light"\n\t]\n}\n'
    data, source, problems = parse_text(text, "model.json")
    assert problems == []
    assert isinstance(data, dict) and data["object"] == "desk_lamp"
    assert source.locate("rules", 0).line == 4


def test_yaml_file_in_flow_style_is_read_as_yaml() -> None:
    text = "{object: desk_lamp, functions: {shade: [diffuse light]}, rules: [diffuse light CAUSES light]}\n"
    data, _, problems = parse_text(text, "model.yaml")
    assert problems == []
    assert data == {
        "object": "desk_lamp",
        "functions": {"shade": ["diffuse light"]},
        "rules": ["diffuse light CAUSES light"],
    }


def test_yaml_with_byte_order_mark_parses() -> None:
    data, _, problems = parse_text("\ufeffobject: desk_lamp\n", "model.yaml")
    assert problems == []
    assert data == {"object": "desk_lamp"}


def test_json_with_byte_order_mark_parses() -> None:
    data, _, problems = parse_text('\ufeff{"object": "desk_lamp"}', "model.json")
    assert problems == []
    assert data == {"object": "desk_lamp"}


def test_empty_document_is_none_without_problems() -> None:
    data, _, problems = parse_text("", "model.yaml")
    assert data is None
    assert problems == []


def test_yaml_tab_indentation_is_syntax_error_at_its_line() -> None:
    data, _, problems = parse_text("object: desk_lamp\nfunctions:\n\tshade: [x]\n", "model.yaml")
    assert data is None
    assert [p.code for p in problems] == ["syntax_error"]
    assert problems[0].location.line == 3
    assert problems[0].location.file == "model.yaml"
    assert "line 3" in problems[0].message
    assert problems[0].hint is not None


def test_yaml_bad_indentation_is_syntax_error_at_its_line() -> None:
    text = "object: desk_lamp\nfunctions:\n  shade: [x]\n light_bulb: [y]\n"
    _, _, problems = parse_text(text, "model.yaml")
    assert [p.code for p in problems] == ["syntax_error"]
    assert problems[0].location.line == 4


def test_yaml_unquoted_colon_in_a_rule_is_syntax_error_at_its_line() -> None:
    text = "object: desk_lamp\nrules:\n  - a CAUSES b: c: d\n"
    _, _, problems = parse_text(text, "model.yaml")
    assert [p.code for p in problems] == ["syntax_error"]
    assert problems[0].location.line == 3
    assert problems[0].hint is not None and "quotes" in problems[0].hint


def test_json_missing_comma_is_syntax_error_at_its_line() -> None:
    text = '{\n  "object": "desk_lamp",\n  "goal": "light"\n  "rules": []\n}\n'
    data, _, problems = parse_text(text, "model.json")
    assert data is None
    assert [p.code for p in problems] == ["syntax_error"]
    assert problems[0].location.line == 4
    assert "JSON" in problems[0].message and "line 4" in problems[0].message


def test_json_trailing_comma_is_syntax_error_at_its_line() -> None:
    text = '{\n  "rules": [\n    "a CAUSES light",\n  ]\n}\n'
    _, _, problems = parse_text(text, "model.json")
    assert [p.code for p in problems] == ["syntax_error"]
    assert problems[0].location.line == 4


def test_recursive_yaml_alias_is_an_error_not_a_crash() -> None:
    # The alias makes a list that holds itself: reading it and locating its values must not recurse
    # forever (the model's check then refuses the shape with invalid_type).
    data, source, problems = parse_text("functions: &loop [*loop]\n", "model.yaml")
    assert problems == []
    assert isinstance(data, dict)
    loop = data["functions"]
    assert loop[0] is loop
    assert source.locate("functions", 0, 0).line == 1


def test_deeply_nested_json_is_an_error_not_a_crash() -> None:
    text = "[" * 5000 + "]" * 5000
    data, _, problems = parse_text(text, "model.json")
    assert data is None
    assert [p.code for p in problems] == ["syntax_error"]


def test_aliases_are_not_expanded_in_the_line_map() -> None:
    # Each level refers to the previous one ten times: 10**4 paths if aliases are walked again.
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, 4)]
    _, source, problems = parse_text("\n".join(lines) + "\n", "model.yaml")
    assert problems == []
    assert len(source.lines) < 100


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=200), st.sampled_from(["model.yaml", "model.json", None]))
def test_parse_text_never_raises(text: str, file_name: str | None) -> None:
    _, source, problems = parse_text(text, file_name)
    assert all(p.code == "syntax_error" for p in problems)
    assert source.file == file_name


# --- files -------------------------------------------------------------------------------------


def test_read_document_reads_a_yaml_file(tmp_path: Path) -> None:
    path = tmp_path / "model.yaml"
    path.write_text(MODEL_YAML, encoding="utf-8")
    data, source, problems = read_document(path)
    assert problems == []
    assert isinstance(data, dict) and data["object"] == "desk_lamp"
    assert source.file == str(path)
    assert source.locate("rules", 1).line == 11


def test_read_document_reads_a_json_file(tmp_path: Path) -> None:
    path = tmp_path / "model.json"
    path.write_text(MODEL_JSON, encoding="utf-8")
    data, source, problems = read_document(path)
    assert problems == []
    assert isinstance(data, dict) and data["object"] == "desk_lamp"
    assert source.locate("rules", 0).line == 8


def test_malformed_file_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "model.yaml"
    path.write_text("object: desk_lamp\nfunctions:\n\tshade: [x]\n", encoding="utf-8")
    _, _, problems = read_document(path)
    assert [p.code for p in problems] == ["syntax_error"]
    assert problems[0].location.file == str(path)
    assert problems[0].location.line == 3


def test_missing_file_is_file_not_found(tmp_path: Path) -> None:
    path = tmp_path / "nowhere.yaml"
    data, _, problems = read_document(path)
    assert data is None
    assert [p.code for p in problems] == ["file_not_found"]
    assert str(path) in problems[0].message
    assert problems[0].location.file == str(path)


def test_folder_is_file_not_found_and_says_folder(tmp_path: Path) -> None:
    data, _, problems = read_document(tmp_path)
    assert data is None
    assert [p.code for p in problems] == ["file_not_found"]
    assert "folder" in problems[0].message


def test_non_utf8_bytes_are_a_syntax_error(tmp_path: Path) -> None:
    path = tmp_path / "model.yaml"
    path.write_bytes(b"object: desk_lamp\ngoal: lumi\xe8re\n")  # Latin-1, not UTF-8
    data, _, problems = read_document(path)
    assert data is None
    assert [p.code for p in problems] == ["syntax_error"]
    assert "UTF-8" in problems[0].message


def test_too_large_file_is_refused_before_reading(tmp_path: Path) -> None:
    path = tmp_path / "model.yaml"
    path.write_bytes(b"#" * (MAX_DOCUMENT_BYTES + 1))
    data, _, problems = read_document(path)
    assert data is None
    assert [p.code for p in problems] == ["file_too_large"]
    assert str(MAX_DOCUMENT_BYTES) in problems[0].message


def test_file_at_the_size_limit_is_read(tmp_path: Path) -> None:
    path = tmp_path / "model.yaml"
    path.write_bytes(b"# padding\n".ljust(MAX_DOCUMENT_BYTES - 20, b"#") + b"\nobject: candle\n")
    data, _, problems = read_document(path)
    assert problems == []
    assert data == {"object": "candle"}


# --- duplicate keys ------------------------------------------------------------------------------


def test_a_yaml_key_named_twice_is_refused_with_its_line() -> None:
    text = "object: desk_lamp\nfunctions: {}\nrules: []\nobject: candle\n"
    data, _, problems = parse_text(text, "model.yaml")
    assert data is None
    assert [p.code for p in problems] == ["duplicate_key"]
    assert "'object'" in problems[0].message
    assert problems[0].location.line == 4


def test_a_nested_yaml_key_named_twice_is_refused() -> None:
    text = "object: desk_lamp\nfunctions:\n  shade: [diffuse light]\n  shade: [hold things together]\n"
    _, _, problems = parse_text(text, "model.yaml")
    assert [(p.code, p.location.line) for p in problems] == [("duplicate_key", 4)]


def test_a_json_key_named_twice_is_refused_with_its_line() -> None:
    text = '{\n  "object": "desk_lamp",\n  "functions": {},\n  "object": "candle"\n}\n'
    data, _, problems = parse_text(text, "model.json")
    assert data is None
    assert [p.code for p in problems] == ["duplicate_key"]
    assert "'object'" in problems[0].message
    assert problems[0].location.line == 4


def test_a_yaml_merge_key_may_override_what_it_merges() -> None:
    data, _, problems = parse_text("base: &b {goal: light}\nmodel:\n  <<: *b\n  goal: heat\n", "m.yaml")
    assert problems == []
    assert data == {"base": {"goal": "light"}, "model": {"goal": "heat"}}


def test_keys_repeated_in_different_mappings_are_fine() -> None:
    data, _, problems = parse_text('{"a": {"x": 1}, "b": {"x": 2}}', "m.json")
    assert problems == []
    assert data == {"a": {"x": 1}, "b": {"x": 2}}


# --- numbers too long to read ---------------------------------------------------------------------

TOO_LONG = "7" * 5000
"""More digits than Python reads from text (4,300): int() raises a bare ValueError."""


def test_a_yaml_integer_too_long_to_read_is_refused_with_its_line() -> None:
    data, _, problems = parse_text(f"object: desk_lamp\nfunctions: {{}}\ngoal: {TOO_LONG}\n", "model.yaml")
    assert data is None
    assert [(p.code, p.location.line) for p in problems] == [("number_too_long", 3)]
    assert "5,000 digits" in problems[0].message and "4,300" in problems[0].message


def test_a_json_integer_too_long_to_read_is_refused_with_its_line() -> None:
    data, _, problems = parse_text(f'{{\n  "object": "desk_lamp",\n  "goal": -{TOO_LONG}\n}}\n', "model.json")
    assert data is None
    assert [(p.code, p.location.line) for p in problems] == [("number_too_long", 3)]


def test_a_long_number_in_quotes_or_a_float_is_read() -> None:
    data, _, problems = parse_text(f'object: "{TOO_LONG}"\nweight: 1.5e+300\n', "model.yaml")
    assert problems == [] and data == {"object": TOO_LONG, "weight": 1.5e300}
