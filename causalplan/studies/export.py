"""An experiment's export: its definition, each participant and each step-3 trial, as the JSON and CSV give them.

``studies.trials`` and ``consensus.participants`` read it back. The records come from the
service's storage; what is read of them is written out below as Protocols.
"""

from __future__ import annotations

import uuid
from collections.abc import Sequence
from datetime import datetime
from typing import Any, Protocol

from causalplan.objects.catalog import Catalog
from causalplan.studies.design import generalization_of
from causalplan.studies.journey import as_utc
from causalplan.studies.recruitment import platform_id_view


class ExportedExperiment(Protocol):
    """What the export reads of a stored experiment."""

    @property
    def id(self) -> uuid.UUID: ...
    @property
    def name(self) -> str: ...
    @property
    def description(self) -> str: ...
    @property
    def created_at(self) -> datetime: ...
    @property
    def design(self) -> dict[str, Any]: ...
    @property
    def is_demo(self) -> bool: ...


class ExportedExclusion(Protocol):
    """What the export reads of a participant's exclusion."""

    @property
    def reason(self) -> str: ...
    @property
    def detail(self) -> str: ...
    @property
    def created_at(self) -> datetime: ...


class ExportedArrival(Protocol):
    """What the export reads of a participant's arrival on the public link."""

    @property
    def platform(self) -> str: ...
    @property
    def platform_id(self) -> str | None: ...
    @property
    def platform_study(self) -> str | None: ...
    @property
    def platform_session(self) -> str | None: ...
    @property
    def decided_at(self) -> datetime | None: ...
    @property
    def client_address(self) -> str | None: ...


class ExportedParticipant(Protocol):
    """What the export reads of a stored participant."""

    @property
    def id(self) -> uuid.UUID: ...
    @property
    def code(self) -> str: ...
    @property
    def experiment_id(self) -> uuid.UUID: ...
    @property
    def condition(self) -> str: ...
    @property
    def ordinal(self) -> int: ...
    @property
    def training_order(self) -> list[str]: ...
    @property
    def test_order(self) -> list[str]: ...
    @property
    def stage(self) -> str: ...
    @property
    def position(self) -> int: ...
    @property
    def work(self) -> dict[str, Any]: ...
    @property
    def model_id(self) -> uuid.UUID | None: ...
    @property
    def created_at(self) -> datetime: ...
    @property
    def started_at(self) -> datetime | None: ...
    @property
    def updated_at(self) -> datetime | None: ...
    @property
    def finished_at(self) -> datetime | None: ...
    @property
    def exclusions(self) -> Sequence[ExportedExclusion]: ...
    @property
    def arrival(self) -> ExportedArrival | None: ...


class ExportedTrial(Protocol):
    """What the export reads of a stored trial."""

    @property
    def id(self) -> uuid.UUID: ...
    @property
    def result(self) -> dict[str, Any]: ...
    @property
    def verdict(self) -> str: ...
    @property
    def decided_by(self) -> str: ...
    @property
    def model_id(self) -> uuid.UUID: ...
    @property
    def mapping(self) -> dict[str, Any]: ...
    @property
    def planner(self) -> str: ...
    @property
    def seconds(self) -> float: ...
    @property
    def created_at(self) -> datetime: ...


class TrialLink(Protocol):
    """Which test object a participant's trial was, and its place in their order (0 = first)."""

    @property
    def test_object(self) -> str: ...
    @property
    def position(self) -> int: ...


class ExportedStepThreeTrial(Protocol):
    """One step-3 trial with its participant and its place in their order."""

    @property
    def link(self) -> TrialLink: ...
    @property
    def participant(self) -> ExportedParticipant: ...
    @property
    def trial(self) -> ExportedTrial: ...


def _iso(value: datetime | None) -> str | None:
    return value.isoformat() if value is not None else None


def experiment_dict(experiment: ExportedExperiment) -> dict[str, Any]:
    """Return an experiment's definition as exported."""
    return {
        "id": str(experiment.id),
        "name": experiment.name,
        "description": experiment.description,
        "created_at": _iso(experiment.created_at),
        "design": experiment.design,
        "is_demo": experiment.is_demo,
    }


def participant_dict(
    participant: ExportedParticipant, progress: str, link: str, platform_ids: str = "plain"
) -> dict[str, Any]:
    """Return one participant as exported: condition, orders, progress, times, exclusions, model and all saved work.

    ``platform_ids``: the crowd platform's ids and the client address consent came from, as
    stored (``plain``), ``hashed``, or ``omit``-ted. The link code and link stay: this is the
    researcher's export (``sharing.shareable`` makes the one to share).
    """
    work = participant.work or {}
    arrival = participant.arrival
    experiment_id = str(participant.experiment_id)
    tutorial = work.get("tutorial", {})
    started, finished = participant.started_at, participant.finished_at
    return {
        "participant_id": str(participant.id),
        "code": participant.code,
        "link": link,
        "condition": participant.condition,
        "ordinal": participant.ordinal,
        "training_order": participant.training_order,
        "test_order": participant.test_order,
        "stage": participant.stage,
        "position": participant.position,
        "progress": progress,
        "created_at": _iso(participant.created_at),
        "started_at": _iso(participant.started_at),
        "updated_at": _iso(participant.updated_at),
        "finished_at": _iso(participant.finished_at),
        "model_id": str(participant.model_id) if participant.model_id else None,
        "excluded": bool(participant.exclusions),
        "exclusion_reason": "; ".join(item.reason for item in participant.exclusions) or None,
        "exclusions": [
            {"reason": item.reason, "detail": item.detail, "created_at": _iso(item.created_at)}
            for item in participant.exclusions
        ],
        "platform": arrival.platform if arrival is not None else None,
        **{
            name: platform_id_view(getattr(arrival, field) if arrival else None, experiment_id, platform_ids)
            for name, field in PLATFORM_FIELDS
        },
        "client_address": platform_id_view(arrival.client_address if arrival else None, experiment_id, platform_ids),
        "consented_at": _iso(arrival.decided_at) if arrival is not None else None,
        "seconds_taken": round((as_utc(finished) - as_utc(started)).total_seconds(), 1)
        if started and finished
        else None,
        "step_seconds": work.get("step_seconds", []),
        "comprehension_tries": len(tutorial.get("tries", [])),
        "comprehension_passed_on_try": tutorial.get("passed_on_try"),
        "demographics": work.get("demographics", {}),
        "model": work.get("model"),
        "work": work,
    }


PLATFORM_FIELDS = (
    ("platform_participant_id", "platform_id"),
    ("platform_study_id", "platform_study"),
    ("platform_session_id", "platform_session"),
)
"""Export column -> arrival field: Prolific's PID, STUDY_ID, SESSION_ID or MTurk's workerId, hitId, assignmentId."""


def trial_dict(stored: ExportedStepThreeTrial, catalog: Catalog) -> dict[str, Any]:
    """Return one step-3 trial as exported: who, which object, the model, the mapping, the verdict and why."""
    participant, trial = stored.participant, stored.trial
    result = trial.result or {}
    return {
        "trial_id": str(trial.id),
        "participant_id": str(participant.id),
        "participant_code": participant.code,
        "condition": participant.condition,
        "training_order": participant.training_order,
        "test_order": participant.test_order,
        "test_object": stored.link.test_object,
        "position": stored.link.position + 1,
        "generalization": generalization_of(participant.training_order, stored.link.test_object, catalog),
        "verdict": trial.verdict,
        "decided_by": trial.decided_by,
        "reasons": result.get("reasons", []),
        "plan": [step.get("text") for step in result.get("plan") or []],
        "model": (participant.work or {}).get("model"),
        "model_id": str(trial.model_id),
        "mapping": trial.mapping,
        "planner": trial.planner,
        "seconds": round(trial.seconds, 4),
        "created_at": _iso(trial.created_at),
        "result": result,
    }


TRIAL_COLUMNS = [
    "trial_id",
    "participant_id",
    "participant_code",
    "condition",
    "training_order",
    "test_order",
    "test_object",
    "position",
    "generalization",
    "verdict",
    "decided_by",
    "reasons",
    "plan",
    "model",
    "model_id",
    "mapping",
    "planner",
    "seconds",
    "created_at",
]
PARTICIPANT_COLUMNS = [
    "participant_id",
    "code",
    "link",
    "condition",
    "ordinal",
    "training_order",
    "test_order",
    "stage",
    "position",
    "progress",
    "created_at",
    "started_at",
    "updated_at",
    "finished_at",
    "model_id",
    "excluded",
    "exclusion_reason",
    "platform",
    "platform_participant_id",
    "platform_study_id",
    "platform_session_id",
    "client_address",
    "consented_at",
    "seconds_taken",
    "step_seconds",
    "comprehension_tries",
    "comprehension_passed_on_try",
    "demographics",
    "model",
    "work",
]
