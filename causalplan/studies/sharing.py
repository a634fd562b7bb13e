"""Data you can share: the export without what opens a participant's pages or names them, as a Psych-DS dataset.

The researcher's own export keeps everything: each participant's link code and link (which
open that participant's pages, completion code included), the client address they consented
from and the crowd platform's raw ids. The shareable export is made from it:

- ``code``, ``link`` and ``client_address`` of each participant, and ``participant_code`` of
  each trial, are removed; any other place a participant's code appears is replaced by
  ``REMOVED`` (a code is a random token, so nothing else matches it);
- the platform ids (Prolific's PID, STUDY_ID and SESSION_ID, MTurk's worker, HIT and
  assignment ids) are replaced by SHA-256 of the experiment's id and the id
  (``recruitment.platform_id_view``), so tables still join, but an id found elsewhere cannot be
  looked up without knowing it;
- its ``shareable`` metadata says all of this.

Laid out as Psych-DS (https://psych-ds.github.io/): ``dataset_description.json`` (schema.org
``Dataset``: name, description, author, license, ``variableMeasured`` naming and describing
every column), ``data/`` with keyword-named CSVs (``study-<id>_table-participants_data.csv``,
``..._table-trials_data.csv``), ``data_dictionary.csv`` (every column of every file with its
type and meaning), and the shareable JSON export itself, which ``causalplan analyze`` reads.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

from causalplan.studies.export import PLATFORM_FIELDS
from causalplan.studies.recruitment import platform_id_view

REMOVED = "[removed]"
PSYCH_DS_VERSION = "Psych-DS 0.4.0"
REMOVED_PARTICIPANT_FIELDS = ("code", "link", "client_address")
REMOVED_TRIAL_FIELDS = ("participant_code",)
HASHED_FIELDS = tuple(name for name, _ in PLATFORM_FIELDS)
DEFAULT_LICENSE = "https://creativecommons.org/licenses/by/4.0/"
SHAREABLE_NOTE = (
    "Shareable export: participants' link codes, links and client addresses are removed; crowd-platform ids "
    "are SHA-256 hashes of the experiment id and the id (the same person has the same hash within this "
    "experiment). Hashing pseudonymises; it does not anonymise: free-text answers stay as participants wrote them."
)

# Every column of the shareable tables: (name, type, description). The data dictionary is written from it.
PARTICIPANT_DICTIONARY: tuple[tuple[str, str, str], ...] = (
    ("participant_id", "text", "The participant's id in this dataset (a random UUID; it opens nothing)."),
    ("condition", "text", "The experiment condition the participant was assigned to."),
    ("ordinal", "integer", "The participant's number within the condition (picks the counterbalanced orders)."),
    ("training_order", "JSON list", "The training objects in the order shown."),
    ("test_order", "JSON list", "The test objects in the order shown."),
    ("stage", "text", "Where the participant is: tutorial, step1, step2, step3, about, done or screened."),
    ("position", "integer", "The object within the stage the participant is at (0 = first)."),
    ("progress", "text", "How far the participant got, in words."),
    ("created_at", "ISO 8601", "When the participant was admitted (or their link made)."),
    ("started_at", "ISO 8601", "When the participant started (admission on the public link)."),
    ("updated_at", "ISO 8601", "When the participant last saved work (empty: never)."),
    ("finished_at", "ISO 8601", "When the participant finished (empty: not finished)."),
    ("model_id", "text", "The id of the participant's causal model among the trials' models (empty: none yet)."),
    ("excluded", "true/false", "Whether screening excluded the participant (screened out or flagged too fast)."),
    ("exclusion_reason", "text", "The exclusion reasons, joined by '; ' (empty when included)."),
    ("platform", "text", "prolific, mturk or direct (no platform ids in the link); empty for links made by hand."),
    ("platform_participant_id", "SHA-256 hex", "Prolific's PROLIFIC_PID or MTurk's workerId, hashed."),
    ("platform_study_id", "SHA-256 hex", "Prolific's STUDY_ID or MTurk's hitId, hashed."),
    ("platform_session_id", "SHA-256 hex", "Prolific's SESSION_ID or MTurk's assignmentId, hashed."),
    ("consented_at", "ISO 8601", "When the participant agreed to take part."),
    ("seconds_taken", "number", "Seconds from start to finish (empty: not finished)."),
    ("step_seconds", "JSON list", "Seconds spent on each page, in the order visited."),
    ("comprehension_tries", "integer", "Tries at the tutorial's comprehension questions."),
    ("comprehension_passed_on_try", "integer", "The try on which every question was right (empty: never)."),
    ("demographics", "JSON object", "Answers to the optional demographic questions."),
    ("model", "JSON object", "The participant's causal model: functions per part and keyword rules."),
    ("work", "JSON object", "Everything the participant saved, step by step."),
)
TRIAL_DICTIONARY: tuple[tuple[str, str, str], ...] = (
    ("trial_id", "text", "The step-3 trial's id."),
    ("participant_id", "text", "Whose trial it is (participant_id of the participants table)."),
    ("condition", "text", "The participant's condition."),
    ("training_order", "JSON list", "The participant's training objects in the order shown."),
    ("test_order", "JSON list", "The participant's test objects in the order shown."),
    ("test_object", "text", "The catalog id of the object the model was tried on."),
    ("position", "integer", "The trial's place in the participant's order of test objects (1 = first)."),
    ("generalization", "text", "near when a training object shares the test object's category, else far."),
    ("verdict", "text", "transfers, fails, invalid or undecided (the planner could not decide in time)."),
    ("decided_by", "text", "What settled the verdict: validation, precheck, planner or simulator."),
    ("reasons", "JSON list", "The verdict's reasons, each with its code and words."),
    ("plan", "JSON list", "The plan's steps in words (empty when there is none)."),
    ("model", "JSON object", "The participant's causal model the trial judged."),
    ("model_id", "text", "The model's id."),
    ("mapping", "JSON object", "The participant's step-3 mapping: functions per part of the test object."),
    ("planner", "text", "The planner that judged the trial."),
    ("seconds", "number", "Seconds the judgement took."),
    ("created_at", "ISO 8601", "When the trial was judged."),
)


@dataclass(frozen=True)
class DataFile:
    """One CSV of the dataset: its path inside the dataset, its columns and its rows."""

    path: str
    columns: tuple[str, ...]
    rows: list[dict[str, Any]]


def shareable(data: dict[str, Any]) -> dict[str, Any]:
    """Return a copy of the researcher's export ``data`` (platform ids as stored) without codes, links,
    addresses and raw platform ids."""
    shared = copy.deepcopy(data)
    experiment_id = str(shared.get("experiment", {}).get("id", ""))
    codes = {str(p["code"]) for p in shared.get("participants", []) if p.get("code")}
    for participant in shared.get("participants", []):
        for name in REMOVED_PARTICIPANT_FIELDS:
            participant.pop(name, None)
        for name in HASHED_FIELDS:
            value = participant.get(name)
            if value is not None:
                participant[name] = platform_id_view(str(value), experiment_id, "hashed")
    for trial in shared.get("trials", []):
        for name in REMOVED_TRIAL_FIELDS:
            trial.pop(name, None)
    cleaned: dict[str, Any] = _without_codes(shared, codes)
    cleaned["shareable"] = {
        "note": SHAREABLE_NOTE,
        "removed": {"participants": list(REMOVED_PARTICIPANT_FIELDS), "trials": list(REMOVED_TRIAL_FIELDS)},
        "hashed": {"fields": list(HASHED_FIELDS), "as": "sha256(experiment_id + ':' + id)"},
    }
    return cleaned


def _without_codes(value: Any, codes: set[str]) -> Any:
    """Return ``value`` with every participant code inside its text replaced by REMOVED."""
    if isinstance(value, str):
        for code in codes:
            if code in value:
                value = value.replace(code, REMOVED)
        return value
    if isinstance(value, list):
        return [_without_codes(item, codes) for item in value]
    if isinstance(value, dict):
        return {_without_codes(key, codes): _without_codes(item, codes) for key, item in value.items()}
    return value


def file_stem(data: dict[str, Any]) -> str:
    """Return the Psych-DS keyword stem of the experiment's files: ``study-<first 8 hex digits of its id>``."""
    return f"study-{str(data['experiment']['id']).replace('-', '')[:8]}"


def data_files(shared: dict[str, Any]) -> list[DataFile]:
    """Return the dataset's CSVs (Psych-DS: in ``data/``, keyword-named, ending ``_data.csv``)."""
    stem = file_stem(shared)
    participant_columns = tuple(name for name, _, _ in PARTICIPANT_DICTIONARY)
    trial_columns = tuple(name for name, _, _ in TRIAL_DICTIONARY)
    return [
        DataFile(f"data/{stem}_table-participants_data.csv", participant_columns, shared.get("participants", [])),
        DataFile(f"data/{stem}_table-trials_data.csv", trial_columns, shared.get("trials", [])),
    ]


def dictionary_rows(shared: dict[str, Any]) -> list[dict[str, str]]:
    """Return the data dictionary: every column of every CSV, with its type and meaning."""
    stem = file_stem(shared)
    files = (
        (f"data/{stem}_table-participants_data.csv", PARTICIPANT_DICTIONARY),
        (f"data/{stem}_table-trials_data.csv", TRIAL_DICTIONARY),
    )
    return [
        {"file": path, "column": name, "type": kind, "description": description}
        for path, dictionary in files
        for name, kind, description in dictionary
    ]


def dataset_description(shared: dict[str, Any], authors: list[str], license_url: str, version: str) -> dict[str, Any]:
    """Return Psych-DS's ``dataset_description.json``: a schema.org Dataset describing every variable."""
    experiment = shared["experiment"]
    described: dict[str, str] = {}
    for name, kind, description in (*PARTICIPANT_DICTIONARY, *TRIAL_DICTIONARY):
        described.setdefault(name, f"{description} ({kind})")
    text = (experiment.get("description") or "").strip()
    return {
        "@context": "https://schema.org/",
        "@type": "Dataset",
        "name": experiment.get("name") or f"causalplan experiment {experiment['id']}",
        "description": (text + "\n\n" if text else "") + SHAREABLE_NOTE,
        "schemaVersion": PSYCH_DS_VERSION,
        "identifier": str(experiment["id"]),
        "dateCreated": shared.get("exported_at"),
        "author": [{"@type": "Person", "name": name} for name in authors],
        "license": license_url,
        "creator": {"@type": "SoftwareApplication", "name": "causalplan", "softwareVersion": version},
        "keywords": ["causal models", "transfer", "far generalization", "planning"],
        "variableMeasured": [
            {"@type": "PropertyValue", "name": name, "description": description}
            for name, description in described.items()
        ],
    }
