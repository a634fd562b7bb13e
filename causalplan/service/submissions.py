"""From a request's documents to valid inputs, and from valid inputs to (cached) answers.

The routes stay thin: they call these, store what is to be stored, and shape the response.
"""

from __future__ import annotations

import hashlib
import json
import time
import uuid
from dataclasses import dataclass
from typing import Any

from sqlalchemy.orm import Session

from causalplan.causal.diagnostics import Report
from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel, Labelling
from causalplan.inputs import mapping_from_data, model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.planners import pipeline
from causalplan.planners.result import PlanStatus
from causalplan.service import worker
from causalplan.service.cache import canonical_model, request_key
from causalplan.service.crud import ClientIds, get_model, new_model_record, save
from causalplan.service.db.models import ModelRecord
from causalplan.service.deps import Services
from causalplan.service.errors import InvalidMappingError, InvalidModelError, LimitExceededError
from causalplan.service.limits import check_labelling_limits, check_model_limits, clean_json
from causalplan.service.schemas import PlanIn
from causalplan.service.settings import Settings
from causalplan.transfer.verdict import Verdict

DEFAULT_PLANNER = "auto"
FALLBACK_PLANNER = "fd"


def resolve_planner(requested: str) -> str:
    """Return the registry name to run for ``requested``; UnknownPlannerError when there is none.

    The registry is read at request time, so planners registered later are accepted as they come.
    """
    names = pipeline.PLANNERS
    if requested == DEFAULT_PLANNER and DEFAULT_PLANNER not in names:
        # 'auto' is the documented default; a registry without it (it came after the service was
        # written) still gets a working default: LAMA-first Fast Downward, as `plan` used to.
        return FALLBACK_PLANNER
    if requested not in names:
        raise pipeline.UnknownPlannerError(
            f"Unknown planner '{requested}'; choose one of: {', '.join([DEFAULT_PLANNER, *names])}.",
            details={"planner": requested, "planners": [DEFAULT_PLANNER, *names]},
        )
    return requested


def default_planner() -> str:
    """Return what the default planner ('auto') runs as, right now."""
    return resolve_planner(DEFAULT_PLANNER)


def resolve_time_limit(requested: float | None, settings: Settings) -> float:
    """Return the solve's time limit; LimitExceededError when it is over the server's maximum."""
    if requested is None:
        return settings.default_time_limit
    if requested > settings.max_time_limit:
        raise LimitExceededError(
            "time_limit_too_long",
            f"time_limit {requested:g} s is over this server's maximum of {settings.max_time_limit:g} s.",
            details={"limit": settings.max_time_limit, "actual": requested, "field": "time_limit"},
        )
    return requested


@dataclass
class ModelSubmission:
    """A model from a request: read and validated, plus the record to store if it came inline."""

    model: CausalModel | None
    report: Report
    record: ModelRecord
    is_new: bool
    """Whether the model came inline (and so is to be stored with the request)."""

    @property
    def is_valid(self) -> bool:
        return self.model is not None and self.report.is_valid


def model_hash(model: CausalModel) -> str:
    """Return the hash of the model's canonical form (equal for models that differ only in layout)."""
    text = json.dumps(canonical_model(model), sort_keys=True, ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8", "replace")).hexdigest()


def read_model(document: dict[str, Any], services: Services, client: ClientIds) -> ModelSubmission:
    """Validate an inline model (limits first, then the reader); return it with its unsaved record."""
    storable = clean_json(document, "the model")  # refuses NaN and deep nesting
    check_model_limits(document, services.settings)
    # The reader sees the text as sent, so a NUL or a lone surrogate is reported as the CLI would.
    loaded = model_from_data(document, SourceMap(), services.catalog)
    model = loaded.model
    record = new_model_record(
        storable,
        model.object_id if model is not None else "",
        loaded.is_valid,
        loaded.report.as_dict(),
        model_hash(model) if model is not None and loaded.is_valid else None,
        client,
    )
    return ModelSubmission(model, loaded.report, record, is_new=True)


def stored_model(session_model: ModelRecord, catalog: Catalog) -> ModelSubmission:
    """Re-read a stored model against the catalog the server has now."""
    loaded = model_from_data(session_model.document, SourceMap(), catalog)
    return ModelSubmission(loaded.model, loaded.report, session_model, is_new=False)


def read_mapping(document: dict[str, Any], services: Services) -> tuple[Labelling | None, Report, dict[str, Any]]:
    """Validate an inline step-3 mapping; return it, its report and the cleaned document."""
    storable = clean_json(document, "the mapping")
    check_labelling_limits(document, services.settings, "mapping")
    loaded = mapping_from_data(document, SourceMap(), services.catalog)
    return loaded.mapping if loaded.is_valid else None, loaded.report, storable


def model_for_request(
    document: dict[str, Any] | None, model_id: uuid.UUID | None, services: Services, session: Session, client: ClientIds
) -> ModelSubmission:
    """Return the request's model: the inline one, or the stored one ``model_id`` names."""
    if document is not None:
        return read_model(document, services, client)
    assert model_id is not None  # the request schema allows exactly one of the two
    return stored_model(get_model(session, model_id), services.catalog)


def invalid_input_error(
    submission: ModelSubmission, mapping_report: Report | None
) -> InvalidModelError | InvalidMappingError | None:
    """Return the 422 error for an invalid model or mapping (None when both are valid)."""
    details: dict[str, object] = {
        "model": submission.report.as_dict(),
        "mapping": mapping_report.as_dict() if mapping_report is not None else None,
        "model_id": str(submission.record.id),
    }
    if not submission.is_valid:
        return InvalidModelError(
            "The model is invalid, so there is nothing to plan: "
            + "; ".join(f"[{d.code}] {d.message}" for d in submission.report.errors[:3]),
            details=details,
        )
    if mapping_report is not None and not mapping_report.is_valid:
        return InvalidMappingError(
            "The step-3 mapping is invalid: " + "; ".join(f"[{d.code}] {d.message}" for d in mapping_report.errors[:3]),
            details=details,
        )
    return None


@dataclass(frozen=True)
class Answer:
    """A planner's answer (a JSON-ready dict), whether it came from the cache, and how long it took."""

    data: dict[str, Any]
    cached: bool
    seconds: float


def plan(services: Services, model: CausalModel, mapping: Labelling | None, planner: str, time_limit: float) -> Answer:
    """Return the plan of ``model`` (on ``mapping``'s object), from the cache or a worker."""
    started = time.perf_counter()
    key = request_key("plan", model, mapping, planner)
    cached = services.cache.get(key)
    if cached is not None:
        return Answer(cached, True, time.perf_counter() - started)
    args = (model, mapping, planner, time_limit, tuple(services.settings.catalog_folders))
    data = services.pool.run(worker.plan_job, args, time_limit + services.settings.solve_grace_seconds)
    if PlanStatus(str(data["status"])).is_final():  # a timeout may go otherwise next time
        services.cache.put(key, data)
    return Answer(data, False, time.perf_counter() - started)


def transfer(services: Services, model: CausalModel, mapping: Labelling, planner: str, time_limit: float) -> Answer:
    """Return the transfer verdict of ``model`` through ``mapping``, from the cache or a worker."""
    started = time.perf_counter()
    key = request_key("transfer", model, mapping, planner)
    cached = services.cache.get(key)
    if cached is not None:
        return Answer(cached, True, time.perf_counter() - started)
    args = (model, mapping, planner, time_limit, tuple(services.settings.catalog_folders))
    data = services.pool.run(worker.transfer_job, args, time_limit + services.settings.solve_grace_seconds)
    if data["verdict"] != Verdict.UNDECIDED.value:
        services.cache.put(key, data)
    return Answer(data, False, time.perf_counter() - started)


def simulate(
    services: Services, model: CausalModel, mapping: Labelling | None, planner: str, time_limit: float, picture: bool
) -> Answer:
    """Return the plan and its simulation report (and picture), from the cache or a worker."""
    started = time.perf_counter()
    key = request_key(f"simulate:{picture}", model, mapping, planner)
    cached = services.cache.get(key)
    if cached is not None:
        return Answer(cached, True, time.perf_counter() - started)
    args = (model, mapping, planner, time_limit, tuple(services.settings.catalog_folders), picture)
    grace = services.settings.solve_grace_seconds + SIMULATION_SECONDS
    data = services.pool.run(worker.simulate_job, args, time_limit + grace)
    planning = data["planning"]
    if isinstance(planning, dict) and PlanStatus(str(planning["status"])).is_final():
        services.cache.put(key, data)
    return Answer(data, False, time.perf_counter() - started)


SIMULATION_SECONDS = 30.0
"""Time a worker gets for the simulation and its picture, beyond the planner's limit."""


def plan_inputs(
    body: PlanIn, services: Services, session: Session, client: ClientIds
) -> tuple[ModelSubmission, Labelling | None, Report | None, str, float]:
    """Read a plan-like request: its model, mapping, planner and time limit.

    An invalid model or mapping raises the 422 error (an inline model is stored first).
    """
    planner = resolve_planner(body.planner)
    time_limit = resolve_time_limit(body.time_limit, services.settings)
    submission = model_for_request(body.model, body.model_id, services, session, client)
    mapping, mapping_report = None, None
    if body.mapping is not None:
        mapping, mapping_report, _ = read_mapping(body.mapping, services)
    problem = invalid_input_error(submission, mapping_report)
    if problem is not None:
        if submission.is_new:
            save(session, [submission.record])
        raise problem
    return submission, mapping, mapping_report, planner, time_limit
