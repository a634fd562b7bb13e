"""Reading and checking a request's documents: limits first, then the reader the CLI uses.

The service's limits bound the work one request can cause (parts, labels, rules); the model
reader checks meaning and reports with the CLI's codes. What a request gives is read once here,
into ``PlanInputs``: a valid model (and the record to store if it came inline), mapping,
planner and time limit. Routes then ask the work layer (``Services.work``) for the answer.
"""

from __future__ import annotations

import json
import re
import uuid
from collections.abc import Callable, Coroutine
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from fastapi import Request, Response
from fastapi.routing import APIRoute

from causalplan.causal.canonical import model_hash
from causalplan.causal.diagnostics import Diagnostic, Report
from causalplan.causal.documents import DuplicateKeyError, SourceMap, located_duplicate_key, refuse_duplicate_keys
from causalplan.causal.model import CausalModel, Labelling
from causalplan.inputs import mapping_from_data, model_from_data
from causalplan.limits import LimitExceededError, check_labelling_limits, check_model_limits
from causalplan.objects.catalog import Catalog
from causalplan.planners import pipeline
from causalplan.service.api.schemas.plans import PlanIn
from causalplan.service.deps import Services, open_session
from causalplan.service.errors import InvalidMappingError, InvalidModelError
from causalplan.service.storage.crud import MAX_NESTING, ClientIds, clean_json, get_model, new_model_record, save
from causalplan.service.storage.records import ModelRecord
from causalplan.settings import Settings

MAX_NUMBER_DIGITS = 100
"""No document needs a longer integer; Python refuses ones over 4,300 digits anyway."""
DEFAULT_PLANNER = "auto"
FALLBACK_PLANNER = "fd"


def resolve_planner(requested: str) -> str:
    """Return the registry name to run for ``requested``; UnknownPlannerError when there is none.

    The registry is read at request time, so planners registered later are accepted as they come.
    """
    names = pipeline.PLANNERS
    if requested == DEFAULT_PLANNER and DEFAULT_PLANNER not in names:
        return FALLBACK_PLANNER  # a registry without 'auto' still gets a working default
    if requested not in names:
        choices = list(dict.fromkeys([DEFAULT_PLANNER, *names]))
        raise pipeline.UnknownPlannerError(
            f"Unknown planner '{requested}'; choose one of: {', '.join(choices)}.",
            details={"planner": requested, "planners": choices},
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


class BodyJSONError(json.JSONDecodeError):
    """A request body this service does not read as JSON, with what is wrong and where (line, column)."""


_BRACKET_OR_STRING = re.compile(r'"(?:[^"\\]+|\\.)*"|[\[\]{}]')


def _nesting(value: Any) -> int:
    """Return how many objects and arrays deep ``value`` nests (0 for a string, a number, ...)."""
    if isinstance(value, dict):
        value = list(value.values())
    if not isinstance(value, list):
        return 0
    return 1 + max((_nesting(item) for item in value), default=0)


def _too_deep(text: str) -> BodyJSONError:
    """Return the error of a body nested too deep, at the first object or array deeper than MAX_NESTING."""
    depth = 0
    for token in _BRACKET_OR_STRING.finditer(text):
        if token.group() in ("[", "{"):
            depth += 1
            if depth > MAX_NESTING:
                return BodyJSONError(f"nested more than {MAX_NESTING} levels deep", text, token.start())
        elif token.group() in ("]", "}"):
            depth -= 1
    return BodyJSONError(f"nested more than {MAX_NESTING} levels deep", text, 0)


def parse_json(body: bytes) -> Any:
    """Return the JSON value of a request body; BodyJSONError says what is wrong and at which line and column.

    ``json.loads`` keeps the last of a key named twice, recurses as deep as a body nests, takes
    integers of thousands of digits and NaN: each is refused here, saying which it is and where.
    """
    try:
        text = body.decode("utf-8")
    except UnicodeDecodeError as exc:
        shown = body.decode("utf-8", "replace")
        at = len(body[: exc.start].decode("utf-8", "replace"))
        raise BodyJSONError(f"not UTF-8 (byte {exc.start})", shown, at) from None

    def integer(digits: str) -> int:
        if len(digits.lstrip("-")) > MAX_NUMBER_DIGITS:
            where = max(text.find(digits), 0)
            raise BodyJSONError(
                f"a number of {len(digits.lstrip('-'))} digits (at most {MAX_NUMBER_DIGITS})", text, where
            )
        return int(digits)

    def constant(name: str) -> Any:
        raise BodyJSONError(f"{name} is not a JSON value", text, max(text.find(name), 0))

    try:
        value = json.loads(text, object_pairs_hook=refuse_duplicate_keys, parse_int=integer, parse_constant=constant)
    except DuplicateKeyError as exc:
        where = located_duplicate_key(text, exc).index or 0
        raise BodyJSONError(f"the key {json.dumps(exc.key)} appears twice in one object", text, where) from None
    except RecursionError:
        raise _too_deep(text) from None
    except BodyJSONError:
        raise
    except json.JSONDecodeError as exc:
        raise BodyJSONError(exc.msg[:1].lower() + exc.msg[1:], text, exc.pos) from None
    if _nesting(value) > MAX_NESTING:
        raise _too_deep(text)
    return value


class StrictJSONRequest(Request):
    """A request whose JSON body is read by ``parse_json``."""

    async def json(self) -> Any:
        if not hasattr(self, "_json"):
            self._json = parse_json(await self.body())
        return self._json


class StrictJSONRoute(APIRoute):
    """A route that reads its JSON body with ``parse_json`` (FastAPI's custom-request pattern)."""

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()

        async def strict_handler(request: Request) -> Response:
            return await handler(StrictJSONRequest(request.scope, request.receive))

        return strict_handler


@dataclass
class ModelSubmission:
    """A model from a request: read and validated, with its record (to store, if it came inline)."""

    model: CausalModel | None
    report: Report
    is_new: bool
    """Whether the model came inline (and so is to be stored with the request)."""
    make_record: Callable[[], ModelRecord]
    """Returns the record: a new one (cleaned for storing) or the stored one; called once, by ``record``."""

    @property
    def is_valid(self) -> bool:
        return self.model is not None and self.report.is_valid

    @cached_property
    def record(self) -> ModelRecord:
        """Return the model's record, made when first asked for: a plan request stores it while its worker plans."""
        return self.make_record()


def _read(document: dict[str, Any], catalog: Catalog) -> tuple[CausalModel | None, Report]:
    # The reader sees the text as sent, so a NUL or a lone surrogate is reported as the CLI would.
    loaded = model_from_data(document, SourceMap(), catalog)
    return loaded.model, loaded.report


def read_model(document: dict[str, Any], services: Services, client: ClientIds) -> ModelSubmission:
    """Check an inline model (limits first, then the reader); return it with its record, made when asked for.

    What is stored is cleaned then (``clean_json`` refuses NaN and deep nesting, which a body
    read by ``parse_json`` never has), so a plan request's path reaches its worker first.
    """
    check_model_limits(document, services.settings)
    model, report = _read(document, services.catalog)
    valid_model = model if model is not None and report.is_valid else None

    def make_record() -> ModelRecord:
        return new_model_record(
            clean_json(document, "the model"),
            model.object_id if model is not None else "",
            valid_model is not None,
            clean_json(report.as_dict()),
            model_hash(valid_model) if valid_model is not None else None,
            client,
            cleaned=True,
        )

    return ModelSubmission(model, report, True, make_record)


def stored_model(record: ModelRecord, catalog: Catalog) -> ModelSubmission:
    """Re-read a stored model against the catalog the server has now."""
    model, report = _read(record.document, catalog)
    return ModelSubmission(model, report, False, lambda: record)


@dataclass(frozen=True)
class MappingRead:
    """What reading a step-3 mapping gave: the mapping when it is valid, its report, and the cleaned document."""

    mapping: Labelling | None
    report: Report
    document: dict[str, Any]


def read_mapping(document: dict[str, Any], services: Services) -> MappingRead:
    """Check an inline step-3 mapping (limits first, then the reader)."""
    storable = clean_json(document, "the mapping")
    check_labelling_limits(document, services.settings, "mapping")
    loaded = mapping_from_data(document, SourceMap(), services.catalog)
    mapping = loaded.mapping if loaded.is_valid else None
    return MappingRead(mapping, loaded.report, storable)


def model_for_request(
    document: dict[str, Any] | None, model_id: uuid.UUID | None, services: Services, client: ClientIds
) -> ModelSubmission:
    """Return the request's model: the inline one, or the stored one ``model_id`` names."""
    if document is not None:
        return read_model(document, services, client)
    assert model_id is not None  # the request schema allows exactly one of the two
    with open_session(services) as session:
        record = get_model(session, model_id)
    return stored_model(record, services.catalog)


def first_errors(report: Report) -> str:
    """Return the report's first three errors with their codes, for an error message."""
    return "; ".join(f"[{d.code}] {d.message}" for d in report.errors[:3])


def invalid_input_error(
    submission: ModelSubmission, mapping_report: Report | None
) -> InvalidModelError | InvalidMappingError | None:
    """Return the 422 error for an invalid model or mapping (None when both are valid)."""
    if submission.is_valid and (mapping_report is None or mapping_report.is_valid):
        return None
    details: dict[str, object] = {
        "model": submission.report.as_dict(),
        "mapping": mapping_report.as_dict() if mapping_report is not None else None,
        "model_id": str(submission.record.id),
    }
    if submission.is_valid and mapping_report is not None:
        return InvalidMappingError("The step-3 mapping is invalid: " + first_errors(mapping_report), details=details)
    return InvalidModelError(
        "The model is invalid, so there is nothing to plan: " + first_errors(submission.report), details=details
    )


@dataclass(frozen=True)
class PlanInputs:
    """A plan-like request, read and valid: its model (and the record to store), mapping, planner and time limit."""

    submission: ModelSubmission
    model: CausalModel
    mapping: Labelling | None
    mapping_report: Report | None
    planner: str
    time_limit: float
    client: ClientIds

    @property
    def warnings(self) -> list[Diagnostic]:
        """Return the validation warnings of the model and the mapping."""
        return [*self.submission.report.warnings, *(self.mapping_report.warnings if self.mapping_report else [])]

    def store(self, services: Services) -> None:
        """Store an inline model's record (a stored model's is stored already)."""
        if self.submission.is_new:
            save(services.engine, [self.submission.record], self.client)


def plan_inputs(body: PlanIn, services: Services, client: ClientIds) -> PlanInputs:
    """Read a plan-like request; an invalid model or mapping raises the 422 error (an inline model is stored first)."""
    planner = resolve_planner(body.planner)
    time_limit = resolve_time_limit(body.time_limit, services.settings)
    submission = model_for_request(body.model, body.model_id, services, client)
    mapping_read = read_mapping(body.mapping, services) if body.mapping is not None else None
    mapping_report = mapping_read.report if mapping_read is not None else None
    problem = invalid_input_error(submission, mapping_report)
    if problem is not None:
        if submission.is_new:
            save(services.engine, [submission.record], client)
        raise problem
    assert submission.model is not None
    mapping = mapping_read.mapping if mapping_read is not None else None
    return PlanInputs(submission, submission.model, mapping, mapping_report, planner, time_limit, client)
