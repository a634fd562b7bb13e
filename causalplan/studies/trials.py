"""An experiment export read into tidy trial rows: one row per step-3 trial, checked field by field.

The export is the JSON file the research pages (and ``GET /v1/experiments/{id}/export``) give:
``{"experiment": {...}, "participants": [...], "trials": [...]}``. Only what the analysis needs
is required of a trial; a field that is missing or of the wrong type is an ``ExportError``
naming the trial and the field, so a hand-edited export fails clearly instead of skewing a rate.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from causalplan.errors import CausalPlanError, UnknownObjectError
from causalplan.objects.catalog import Catalog
from causalplan.studies.design import Design
from causalplan.transfer.generalization import near_or_far

VERDICTS = ("transfers", "fails", "invalid", "undecided")


class ExportError(CausalPlanError):
    """An experiment export cannot be analysed: not JSON, or a trial lacks a field the analysis needs."""

    code = "invalid_export"


@dataclass(frozen=True)
class TrialRow:
    """One step-3 trial, as the analysis sees it."""

    trial_id: str
    participant_id: str
    condition: str
    training_objects: tuple[str, ...]
    test_object: str
    test_category: str
    trained_category: bool
    generalization: str
    position: int
    verdict: str
    decided_by: str
    reason_codes: tuple[str, ...]
    model: Mapping[str, Any] | None
    mapping: Mapping[str, Any] | None
    excluded: bool
    exclusion_reason: str | None

    @property
    def outcome(self) -> int | None:
        """Return 1 when the model transferred, 0 when it did not (fails or invalid), None when undecided."""
        if self.verdict == "undecided":
            return None
        return 1 if self.verdict == "transfers" else 0


def _field(item: Mapping[str, Any], name: str, kind: type | tuple[type, ...], where: str) -> Any:
    value = item.get(name)
    if not isinstance(value, kind):
        expected = kind.__name__ if isinstance(kind, type) else " or ".join(k.__name__ for k in kind)
        raise ExportError(f"{where}.{name} must be {expected}; got {type(value).__name__}.", details={"at": where})
    return value


def _names(value: Sequence[Any], where: str) -> tuple[str, ...]:
    if not all(isinstance(item, str) for item in value):
        raise ExportError(f"{where} must be a list of object ids.", details={"at": where})
    return tuple(value)


def _reason_codes(reasons: object, where: str) -> tuple[str, ...]:
    if not isinstance(reasons, list):
        raise ExportError(f"{where}.reasons must be a list.", details={"at": where})
    codes = []
    for reason in reasons:
        code = reason.get("code") if isinstance(reason, dict) else reason
        if not isinstance(code, str):
            raise ExportError(f"{where}.reasons holds an entry without a code.", details={"at": where})
        codes.append(code)
    return tuple(codes)


@dataclass(frozen=True)
class Study:
    """What an export gives the analysis: its trials, its design when it has one, who was screened out."""

    rows: tuple[TrialRow, ...]
    design: Design | None = None
    exclusions: Mapping[str, str] | None = None
    """Participant id -> why they were excluded, those without trials too (None: only what the rows say)."""


def _exclusions(participants: object) -> dict[str, str]:
    """Return the participants screened out, with their reason (an export may not say any)."""
    if not isinstance(participants, list):
        return {}
    excluded = {}
    for participant in participants:
        if isinstance(participant, dict) and participant.get("excluded"):
            excluded[str(participant.get("participant_id"))] = str(participant.get("exclusion_reason") or "excluded")
    return excluded


def trial_rows(export: Mapping[str, Any], catalog: Catalog) -> list[TrialRow]:
    """Return the export's trials as rows; raise ExportError for the first trial that cannot be read."""
    trials = export.get("trials")
    if not isinstance(trials, list):
        raise ExportError("The export has no 'trials' list: is it an experiment export (JSON)?")
    excluded = _exclusions(export.get("participants"))
    rows = []
    for index, item in enumerate(trials):
        where = f"trials[{index}]"
        if not isinstance(item, dict):
            raise ExportError(f"{where} must be an object.", details={"at": where})
        training = _names(_field(item, "training_order", list, where), f"{where}.training_order")
        test = _field(item, "test_object", str, where)
        verdict = _field(item, "verdict", str, where)
        if verdict not in VERDICTS:
            raise ExportError(
                f"{where}.verdict is '{verdict}'; expected one of {', '.join(VERDICTS)}.", details={"at": where}
            )
        try:
            test_category = catalog.get(test).category
            trained = {catalog.get(name).category for name in training}
        except UnknownObjectError as exc:
            raise ExportError(
                f"{where}: {exc.message} (add its folder with --catalog).", details={"at": where}
            ) from exc
        participant = str(_field(item, "participant_id", str, where))
        model, mapping = item.get("model"), item.get("mapping")
        rows.append(
            TrialRow(
                trial_id=str(item.get("trial_id") or f"trial-{index}"),
                participant_id=participant,
                condition=_field(item, "condition", str, where),
                training_objects=training,
                test_object=test,
                test_category=test_category,
                trained_category=test_category in trained,
                generalization=near_or_far(trained, test_category),
                position=int(item.get("position") or 0),
                verdict=verdict,
                decided_by=str(item.get("decided_by") or ""),
                reason_codes=_reason_codes(item.get("reasons", []), where),
                model=model if isinstance(model, dict) else None,
                mapping=mapping if isinstance(mapping, dict) else None,
                excluded=participant in excluded,
                exclusion_reason=excluded.get(participant),
            )
        )
    return rows


def _design(experiment: object) -> Design | None:
    """Return the export's design (None when it has none, as a synthetic or hand-made export may not)."""
    design = experiment.get("design") if isinstance(experiment, dict) else None
    if design is None:
        return None
    try:
        return Design.from_dict(design)
    except (KeyError, TypeError, AttributeError) as exc:
        raise ExportError(
            "experiment.design must hold conditions, each with a name, training and test objects.",
            details={"at": "experiment.design"},
        ) from exc


def read_study(export: Mapping[str, Any], catalog: Catalog) -> Study:
    """Return the export's trials as rows with its design and exclusions; raise ExportError as ``trial_rows`` does."""
    return Study(
        tuple(trial_rows(export, catalog)), _design(export.get("experiment")), _exclusions(export.get("participants"))
    )


def read_export(path: Path) -> dict[str, Any]:
    """Return the parsed export file; raise ExportError when it cannot be read or is not a JSON object."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ExportError(f"Cannot read {path}: {exc.strerror}.", details={"file": str(path)}) from exc
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ExportError(f"{path} is not a JSON export: {exc}.", details={"file": str(path)}) from exc
    if not isinstance(data, dict):
        raise ExportError(f"{path} holds a JSON {type(data).__name__}, not an experiment export.")
    return data
