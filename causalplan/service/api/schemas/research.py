"""Answers of /v1/trials and /v1/export."""

from __future__ import annotations

import uuid
from datetime import datetime
from typing import Any

from causalplan.service.api.schemas.common import OutputModel, UtcDatetime


class TrialOut(OutputModel):
    """One stored transfer trial."""

    id: uuid.UUID
    created_at: UtcDatetime
    participant_id: str | None
    session_id: str | None
    model_id: uuid.UUID
    training_object: str | None
    test_object: str | None
    planner: str
    verdict: str
    generalization: str | None
    decided_by: str
    cached: bool
    seconds: float
    mapping: dict[str, Any]
    result: dict[str, Any]


class TrialsOut(OutputModel):
    """A page of trials, newest first, and how many match in all."""

    data: list[TrialOut]
    count: int


class StoredModelOut(OutputModel):
    """One stored model in an export."""

    id: uuid.UUID
    created_at: UtcDatetime
    participant_id: str | None
    session_id: str | None
    object_id: str
    is_valid: bool
    canonical_hash: str | None
    document: dict[str, Any]
    report: dict[str, Any]


class ExportOut(OutputModel):
    """Everything stored: every model and every trial."""

    exported_at: datetime
    models: list[StoredModelOut]
    trials: list[TrialOut]
