"""A crowd's participants read from a trials file (as ``batch`` reads) or an experiment export.

A trials file has one ``{"id", "model", "mapping"}`` a line (JSON Lines), or a JSON/YAML list of
them; the mapping may be absent (a participant who only built a model), and lines with the same
id are one participant with several test objects. An experiment export (the research page's
JSON export) has ``participants`` with their ``model`` and ``trials`` with each ``mapping``.
An entry that cannot be used is kept with the reason, so a report can say who was left out.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from causalplan.causal.documents import NumberTooLongError, read_document, read_integer
from causalplan.errors import InputFileError


@dataclass
class Participant:
    """One person: the model as data, their step-3 mappings by test object, and where they came from."""

    id: str
    model: object
    mappings: dict[str, object] = field(default_factory=dict)
    where: str = ""
    problems: list[str] = field(default_factory=list)


def read_participants(path: Path) -> list[Participant]:
    """Return the participants of a trials file or an experiment export, in the order first seen."""
    if path.suffix.lower() == ".jsonl":
        return _group(_json_lines(path))
    data, _source, problems = read_document(path)
    if problems:
        line = problems[0].location.line
        raise InputFileError(f"{path} could not be read{f' (line {line})' if line else ''}: {problems[0].message}")
    if isinstance(data, dict) and "participants" in data:
        return _from_export(data, path)
    if not isinstance(data, list):
        raise InputFileError(
            f"{path} is neither a list of trials, a JSON Lines file (*.jsonl) nor an experiment export "
            "(a JSON object with 'participants' and 'trials')."
        )
    return _group((f"entry {index}", entry) for index, entry in enumerate(data, start=1))


def _json_lines(path: Path) -> list[tuple[str, object]]:
    try:
        raw_lines = path.read_bytes().splitlines()
    except OSError as exc:
        raise InputFileError(f"{path} could not be read: {exc.strerror}.") from exc
    entries: list[tuple[str, object]] = []
    for number, raw in enumerate(raw_lines, start=1):
        if not raw.strip():
            continue
        where = f"line {number}"
        try:
            entries.append((where, json.loads(raw.decode("utf-8-sig"), parse_int=read_integer)))
        except NumberTooLongError as exc:
            entries.append((where, _Unreadable(f"{where} holds {exc}")))
        except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
            entries.append((where, _Unreadable(f"{where} is not a JSON object ({type(exc).__name__})")))
    return entries


@dataclass(frozen=True)
class _Unreadable:
    why: str


def _group(entries: Iterable[tuple[str, object]]) -> list[Participant]:
    """Return one participant per id; a second line of an id adds a mapping (its model must agree)."""
    people: dict[str, Participant] = {}
    for where, entry in entries:
        if isinstance(entry, _Unreadable):
            people[where] = Participant(where, None, where=where, problems=[entry.why])
            continue
        if not isinstance(entry, dict) or "model" not in entry:
            people[where] = Participant(where, None, where=where, problems=[f"{where} has no 'model'"])
            continue
        person_id = str(entry.get("id", where))
        person = people.setdefault(person_id, Participant(person_id, entry["model"], where=where))
        if person.model != entry["model"]:
            person.problems.append(f"{where} gives {person_id} a different model than {person.where}; it is ignored")
            continue
        _add_mapping(person, entry.get("mapping"), where)
    return list(people.values())


def _add_mapping(person: Participant, mapping: object, where: str) -> None:
    if mapping is None:
        return
    test = mapping.get("object") if isinstance(mapping, dict) else None
    if not isinstance(test, str):
        person.problems.append(f"the mapping at {where} names no test object; it is ignored")
    elif test in person.mappings:
        person.problems.append(f"{where} maps {test} a second time for {person.id}; the first is kept")
    else:
        person.mappings[test] = mapping


def _first(training_order: object) -> str | None:
    return str(training_order[0]) if isinstance(training_order, list) and training_order else None


def _file_schema(model: object, training: str | None) -> object:
    """Return a participant's model as a model file: the research pages keep labels per training object.

    Their form is ``{"goal", "functions": {object: {part: labels}}, "rules"}``; a model of two
    training objects gives the one of the first it was shown (a consensus is of one training
    object). A model already in the file schema, or one that is not a dict, is returned as it is.
    """
    if not isinstance(model, dict) or "object" in model or not isinstance(model.get("functions"), dict):
        return model
    per_object = model["functions"]
    if not per_object or not all(isinstance(parts, dict) for parts in per_object.values()):
        return model
    object_id = training if training in per_object else next(iter(per_object))
    parts = per_object[object_id]
    return {
        "object": object_id,
        "goal": model.get("goal", "light"),
        "functions": {part: labels for part, labels in parts.items() if labels},
        "rules": model.get("rules", []),
    }


def participants_of_export(data: dict[str, object], where: str) -> list[Participant]:
    """Return the participants of an experiment export already parsed (``where`` names it in errors)."""
    return _from_export(data, Path(where))


def _from_export(data: dict[str, object], path: Path) -> list[Participant]:
    """Return the participants of an experiment export: each model, and every trial's mapping."""
    people: dict[str, Participant] = {}
    participants = data.get("participants")
    if not isinstance(participants, list):
        raise InputFileError(f"{path}: 'participants' is not a list.")
    for index, entry in enumerate(participants, start=1):
        if not isinstance(entry, dict):
            continue
        person_id = str(entry.get("code") or entry.get("participant_id") or f"participant {index}")
        key = str(entry.get("participant_id", person_id))
        model = _file_schema(entry.get("model"), _first(entry.get("training_order")))
        person = Participant(person_id, model, where=f"participant {index}")
        if model is None:
            person.problems.append(f"{person_id} has no model yet")
        people[key] = person
    trials = data.get("trials", [])
    for index, trial in enumerate(trials if isinstance(trials, list) else [], start=1):
        if not isinstance(trial, dict):
            continue
        mapper = people.get(str(trial.get("participant_id")))
        if mapper is not None:
            _add_mapping(mapper, trial.get("mapping"), f"trial {index}")
    return list(people.values())
