"""The shareable export: what is removed, what is hashed, and the Psych-DS description."""

from __future__ import annotations

import json
from typing import Any

from causalplan.studies.export import PARTICIPANT_COLUMNS, TRIAL_COLUMNS
from causalplan.studies.recruitment import platform_id_view
from causalplan.studies.sharing import (
    PARTICIPANT_DICTIONARY,
    REMOVED,
    REMOVED_PARTICIPANT_FIELDS,
    REMOVED_TRIAL_FIELDS,
    TRIAL_DICTIONARY,
    data_files,
    dataset_description,
    shareable,
)

EXPERIMENT = "0b7e2c1a-1111-4222-8333-444455556666"


def private_export() -> dict[str, Any]:
    participant = {
        "participant_id": "p-1",
        "code": "Secr3tCode42xyz",
        "link": "https://study.example/p/Secr3tCode42xyz",
        "client_address": "203.0.113.4",
        "platform_participant_id": "5f1e2d3c4b5a697887766554",
        "platform_study_id": "study-9",
        "platform_session_id": "sess-1",
        "work": {"note": "opened /p/Secr3tCode42xyz/step2 twice"},
    }
    trial = {"trial_id": "t-1", "participant_id": "p-1", "participant_code": "Secr3tCode42xyz", "verdict": "fails"}
    return {
        "exported_at": "2026-12-05T06:00:00+00:00",
        "experiment": {"id": EXPERIMENT, "name": "lamp", "description": ""},
        "participants": [participant],
        "trials": [trial],
    }


def test_codes_links_and_addresses_go_and_platform_ids_are_hashed_per_experiment() -> None:
    data = private_export()
    shared = shareable(data)
    text = json.dumps(shared)
    assert "Secr3tCode42xyz" not in text and "203.0.113.4" not in text
    (participant,) = shared["participants"]
    assert participant["work"]["note"] == f"opened /p/{REMOVED}/step2 twice"
    assert participant["platform_participant_id"] == platform_id_view("5f1e2d3c4b5a697887766554", EXPERIMENT, "hashed")
    assert data["participants"][0]["code"] == "Secr3tCode42xyz"  # the researcher's copy is untouched
    assert "participant_code" not in shared["trials"][0]


def test_every_column_the_export_keeps_is_in_the_data_dictionary() -> None:
    assert [name for name, _, _ in PARTICIPANT_DICTIONARY] == [
        name for name in PARTICIPANT_COLUMNS if name not in REMOVED_PARTICIPANT_FIELDS
    ]
    assert [name for name, _, _ in TRIAL_DICTIONARY] == [
        name for name in TRIAL_COLUMNS if name not in REMOVED_TRIAL_FIELDS
    ]


def test_the_description_is_a_schema_org_dataset_with_every_variable() -> None:
    shared = shareable(private_export())
    description = dataset_description(shared, ["A. Researcher"], "CC0-1.0", "1.0")
    assert {"@context", "@type", "name", "description", "variableMeasured", "author", "license"} <= set(description)
    names = [variable["name"] for variable in description["variableMeasured"]]
    assert len(names) == len(set(names)) and "verdict" in names and "code" not in names
    assert [file.path for file in data_files(shared)] == [
        "data/study-0b7e2c1a_table-participants_data.csv",
        "data/study-0b7e2c1a_table-trials_data.csv",
    ]
