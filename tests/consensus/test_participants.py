"""Reading a crowd: trials files as batch reads them, with absent mappings, and experiment exports."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from causalplan.consensus.participants import read_participants
from causalplan.errors import InputFileError

MODEL = {
    "object": "desk_lamp",
    "functions": {"base_with_cables": ["provide electricity"], "light_bulb": ["glow"]},
    "rules": ["provide electricity AND glow CAUSES light"],
}
FLASHLIGHT = {"object": "flashlight", "functions": {"batteries": ["provide electricity"], "head": ["glow"]}}
CANDLE = {"object": "candle", "functions": {"wax": ["provide electricity"], "wick": ["glow"]}}


def write_lines(path: Path, lines: list[object]) -> Path:
    path.write_text("".join((line if isinstance(line, str) else json.dumps(line)) + "\n" for line in lines))
    return path


def test_lines_with_one_id_are_one_participant_with_several_test_objects(tmp_path: Path) -> None:
    path = write_lines(
        tmp_path / "t.jsonl",
        [
            {"id": "ann", "model": MODEL, "mapping": FLASHLIGHT},
            {"id": "ann", "model": MODEL, "mapping": CANDLE},
            {"id": "bob", "model": MODEL},
        ],
    )
    people = read_participants(path)
    assert [(p.id, sorted(p.mappings)) for p in people] == [("ann", ["candle", "flashlight"]), ("bob", [])]


def test_an_unreadable_line_is_kept_with_where_and_why(tmp_path: Path) -> None:
    path = write_lines(tmp_path / "t.jsonl", ["{not json", {"id": "ann", "model": MODEL}, {"id": "x"}])
    people = read_participants(path)
    assert [(p.id, p.model is None, p.problems) for p in people] == [
        ("line 1", True, ["line 1 is not a JSON object (JSONDecodeError)"]),
        ("ann", False, []),
        ("line 3", True, ["line 3 has no 'model'"]),
    ]


def test_a_second_line_with_another_model_for_the_same_id_is_ignored_and_said(tmp_path: Path) -> None:
    other = {**MODEL, "rules": ["provide electricity CAUSES light"]}
    path = write_lines(
        tmp_path / "t.jsonl", [{"id": "ann", "model": MODEL}, {"id": "ann", "model": other, "mapping": CANDLE}]
    )
    (ann,) = read_participants(path)
    assert ann.mappings == {}
    assert ann.problems == ["line 2 gives ann a different model than line 1; it is ignored"]


def test_an_experiment_export_gives_each_participant_their_model_and_trial_mappings(tmp_path: Path) -> None:
    # The shape of the research page's JSON export (studies/export.py).
    export = {
        "exported_at": "2026-12-01T00:00:00+00:00",
        "experiment": {"id": "e1", "name": "pilot"},
        "rates": [],
        "participants": [
            {"participant_id": "u1", "code": "P-1", "model": MODEL, "work": {"model": MODEL}},
            {"participant_id": "u2", "code": "P-2", "model": None, "work": {}},
        ],
        "trials": [
            {"trial_id": "t1", "participant_id": "u1", "test_object": "flashlight", "mapping": FLASHLIGHT},
            {"trial_id": "t2", "participant_id": "u1", "test_object": "candle", "mapping": CANDLE},
        ],
    }
    path = tmp_path / "export.json"
    path.write_text(json.dumps(export))
    people = read_participants(path)
    assert [(p.id, sorted(p.mappings), p.problems) for p in people] == [
        ("P-1", ["candle", "flashlight"], []),
        ("P-2", [], ["P-2 has no model yet"]),
    ]


def test_a_file_that_is_no_crowd_says_what_it_should_be(tmp_path: Path) -> None:
    path = tmp_path / "x.json"
    path.write_text('{"hello": 1}')
    with pytest.raises(InputFileError, match="neither a list of trials"):
        read_participants(path)


def test_a_research_page_model_is_read_as_the_model_file_of_its_first_training_object() -> None:
    from causalplan.consensus.participants import participants_of_export

    web_model = {
        "goal": "light",
        "functions": {"candle": {"wick": ["burn"]}, "desk_lamp": {"light_bulb": ["glow"], "shade": []}},
        "rules": ["glow CAUSES light"],
    }
    export = {"participants": [{"participant_id": "p1", "training_order": ["desk_lamp", "candle"], "model": web_model}]}
    (person,) = participants_of_export(export, "an export")
    assert person.model == {
        "object": "desk_lamp",
        "goal": "light",
        "functions": {"light_bulb": ["glow"]},
        "rules": ["glow CAUSES light"],
    }


def test_a_line_with_a_number_too_long_to_read_is_left_out_with_its_reason(tmp_path: Path) -> None:
    path = write_lines(
        tmp_path / "t.jsonl", [{"id": "ann", "model": MODEL}, '{"id": "bob", "model": ' + "7" * 5000 + "}"]
    )
    people = read_participants(path)
    assert [(p.id, p.problems) for p in people] == [
        ("ann", []),
        ("line 2", ["line 2 holds a number of 5,000 digits (at most 4,300 can be read)"]),
    ]


def test_a_list_file_with_a_number_too_long_is_an_input_error_naming_its_line(tmp_path: Path) -> None:
    path = tmp_path / "crowd.json"
    path.write_text('[\n  {"id": "ann", "model": ' + "7" * 5000 + "}\n]\n")
    with pytest.raises(InputFileError, match=r"\(line 2\).*5,000 digits"):
        read_participants(path)
