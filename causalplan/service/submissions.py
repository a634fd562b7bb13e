"""From a request's documents to valid inputs, and from valid inputs to (cached) answers.

The routes stay thin: they call these, store what is to be stored, and shape the response.
"""

from __future__ import annotations

import hashlib
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

from causalplan.causal.diagnostics import Diagnostic, Report
from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel, Labelling
from causalplan.inputs import LoadedModel, mapping_from_data, model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task
from causalplan.pddl.writer import compile_task
from causalplan.planners import pipeline
from causalplan.planners.result import PlanStatus
from causalplan.service import worker
from causalplan.service.cache import (
    answer_key,
    canonical_labelling,
    canonical_model,
    canonical_text,
    document_key,
    request_key,
)
from causalplan.service.crud import (
    ClientIds,
    get_model,
    new_model_record,
    new_trial_record,
    save,
)
from causalplan.service.db.models import ModelRecord, TrialRecord
from causalplan.service.deps import Services, open_session
from causalplan.service.errors import InvalidMappingError, InvalidModelError, LimitExceededError
from causalplan.service.limits import check_labelling_limits, check_model_limits, clean_json
from causalplan.service.planning import SentJob
from causalplan.service.schemas import PlanIn, TransferIn
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
        choices = list(dict.fromkeys([DEFAULT_PLANNER, *names]))  # 'auto' once, whether or not the registry has it
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


@dataclass(frozen=True)
class ModelRead(LoadedModel):
    """What reading and validating a model document gave: the same for every request that sends it."""

    report_data: dict[str, Any]
    """The report as JSON, cleaned (``clean_json``): ready to store."""
    canonical: str | None
    """The canonical text of a valid model (its hash is stored; answers are keyed by it)."""


@dataclass(frozen=True)
class MappingRead:
    """What reading and validating a step-3 mapping document gave: the same for every request that sends it."""

    mapping: Labelling | None
    """The mapping when it is valid (None otherwise)."""
    report: Report
    canonical: str | None


@dataclass
class ModelSubmission:
    """A model from a request: read and validated, plus the record to store if it came inline."""

    model: CausalModel | None
    report: Report
    record: ModelRecord
    is_new: bool
    """Whether the model came inline (and so is to be stored with the request)."""
    canonical: str | None = None
    """The canonical text of a valid model (see ``ModelRead``)."""

    @property
    def is_valid(self) -> bool:
        return self.model is not None and self.report.is_valid


def model_text(model: CausalModel) -> str:
    """Return the model's canonical text: equal for models that differ only in layout."""
    return canonical_text(canonical_model(model))


def text_hash(canonical: str) -> str:
    """Return the stored hash of a model's canonical text."""
    return hashlib.sha256(canonical.encode("utf-8", "replace")).hexdigest()


def model_hash(model: CausalModel) -> str:
    """Return the hash of the model's canonical form (equal for models that differ only in layout)."""
    return text_hash(model_text(model))


def _model_read(document: dict[str, Any], catalog: Catalog) -> ModelRead:
    # The reader sees the text as sent, so a NUL or a lone surrogate is reported as the CLI would.
    loaded = model_from_data(document, SourceMap(), catalog)
    canonical = model_text(loaded.model) if loaded.model is not None and loaded.is_valid else None
    return ModelRead(loaded.model, loaded.report, clean_json(loaded.report.as_dict()), canonical)


def _read_model_document(document: dict[str, Any], services: Services) -> ModelRead:
    check_model_limits(document, services.settings)
    return _model_read(document, services.catalog)


def read_model(document: dict[str, Any], services: Services, client: ClientIds) -> ModelSubmission:
    """Validate an inline model (limits first, then the reader); return it with its unsaved record.

    A document read before (the same JSON) is not read again: the reader's answer is kept.
    """
    storable = clean_json(document, "the model")  # refuses NaN and deep nesting
    key, size = document_key("model", document)
    read = services.reads.get(key)
    if not isinstance(read, ModelRead):
        read = _read_model_document(document, services)
        services.reads.put(key, read, size)
    return _inline_submission(storable, read, client)


def _inline_submission(storable: dict[str, Any], read: ModelRead, client: ClientIds) -> ModelSubmission:
    """Return an inline model's submission: what reading it gave, and its record to store.

    ``storable``: the document, cleaned (``clean_json``).
    """
    model = read.model
    record = new_model_record(
        storable,
        model.object_id if model is not None else "",
        read.is_valid,
        read.report_data,
        text_hash(read.canonical) if read.canonical is not None else None,
        client,
        cleaned=True,
    )
    return ModelSubmission(model, read.report, record, is_new=True, canonical=read.canonical)


def stored_model(record: ModelRecord, services: Services) -> ModelSubmission:
    """Re-read a stored model against the catalog the server has now (a document read before is not read again)."""
    key, size = document_key("stored model", record.document)
    read = services.reads.get(key)
    if not isinstance(read, ModelRead):
        read = _model_read(record.document, services.catalog)
        services.reads.put(key, read, size)
    return ModelSubmission(read.model, read.report, record, is_new=False, canonical=read.canonical)


def _read_mapping_document(document: dict[str, Any], services: Services) -> MappingRead:
    check_labelling_limits(document, services.settings, "mapping")
    loaded = mapping_from_data(document, SourceMap(), services.catalog)
    if not loaded.is_valid or loaded.mapping is None:
        return MappingRead(None, loaded.report, None)
    return MappingRead(loaded.mapping, loaded.report, canonical_text(canonical_labelling(loaded.mapping)))


def read_mapping(document: dict[str, Any], services: Services) -> tuple[MappingRead, dict[str, Any]]:
    """Validate an inline step-3 mapping; return what reading it gave and the cleaned document.

    A document read before (the same JSON) is not read again.
    """
    storable = clean_json(document, "the mapping")
    key, size = document_key("mapping", document)
    read = services.reads.get(key)
    if not isinstance(read, MappingRead):
        read = _read_mapping_document(document, services)
        services.reads.put(key, read, size)
    return read, storable


def model_for_request(
    document: dict[str, Any] | None, model_id: uuid.UUID | None, services: Services, client: ClientIds
) -> ModelSubmission:
    """Return the request's model: the inline one, or the stored one ``model_id`` names.

    A session is opened only to read a stored model (~0.04 ms that an inline model does not need).
    """
    if document is not None:
        return read_model(document, services, client)
    assert model_id is not None  # the request schema allows exactly one of the two
    with open_session(services) as session:
        record = get_model(session, model_id)
    return stored_model(record, services)


def storing(services: Services, submission: ModelSubmission) -> Callable[[], None] | None:
    """Return what stores an inline model's record (None for a stored model): to run while a worker solves."""
    if not submission.is_new:
        return None
    return partial(save, services.engine, [submission.record])


def first_errors(report: Report) -> str:
    """Return the report's first three errors with their codes, for an error message."""
    return "; ".join(f"[{d.code}] {d.message}" for d in report.errors[:3])


def invalid_input_error(
    submission: ModelSubmission, mapping_report: Report | None
) -> InvalidModelError | InvalidMappingError | None:
    """Return the 422 error for an invalid model or mapping (None when both are valid)."""
    if submission.is_valid and (mapping_report is None or mapping_report.is_valid):
        return None  # the common case: no report is turned into JSON
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
class Answer:
    """A planner's answer (a JSON-ready dict), whether it came from the cache, and how long it took."""

    data: dict[str, Any]
    cached: bool
    seconds: float


SIMULATION_SECONDS = 30.0
"""Time a worker gets for the simulation and its picture, beyond the planner's limit."""


def _key(
    services: Services, kind: str, model: CausalModel, mapping: Labelling | None, planner: str, limit: float
) -> str:
    return request_key(kind, model, mapping, planner, limit, services.catalog_key)


@dataclass(frozen=True)
class PendingAnswer:
    """An answer a worker is working on: waited for in a thread (``wait``) or on the event loop (``reply``).

    Once there, it is kept for its key if it is final (``_start``'s ``is_final``).
    """

    services: Services
    key: str
    job: SentJob[dict[str, Any]]
    is_final: Callable[[dict[str, Any]], bool]
    started: float

    def wait(self) -> Answer:
        """Wait here for the worker's answer (see ``PlannerPool.submit`` for its errors)."""
        return self._kept(self.job.wait())

    async def reply(self) -> Answer:
        """Wait on the event loop for the worker's answer (see ``PlannerPool.submit`` for its errors)."""
        return self._kept(await self.job.reply())

    def abandon(self) -> None:
        """Give up the answer unread: its worker is replaced (the next job must not get this answer)."""
        self.job.abandon()

    def _kept(self, data: dict[str, Any]) -> Answer:
        if self.is_final(data):
            self.services.cache.put(self.key, data)
        return Answer(data, False, time.perf_counter() - self.started)


def _start(
    services: Services,
    key: str,
    job: Callable[..., dict[str, Any]],
    args: tuple[Any, ...],
    seconds: float,
    is_final: Callable[[dict[str, Any]], bool],
    meanwhile: Callable[[], None] | None = None,
) -> Answer | PendingAnswer:
    """Return the answer kept for ``key``, or send ``job(*args)`` to a worker for at most ``seconds``.

    Blocks while no worker is free: call it in a thread. A new answer is kept only when
    ``is_final``: a timeout may go otherwise next time. ``meanwhile`` (e.g. storing the
    request's record) runs while the worker solves, or first when the answer is kept; it runs
    unless the request is refused before a worker takes it.
    """
    started = time.perf_counter()
    cached = services.cache.get(key)
    if cached is not None:
        if meanwhile is not None:
            meanwhile()
        return Answer(cached, True, time.perf_counter() - started)
    return PendingAnswer(services, key, services.pool.submit(job, args, seconds, meanwhile), is_final, started)


def waited(answer: Answer | PendingAnswer) -> Answer:
    """Return ``answer``, waited for here if a worker is still working on it."""
    return answer if isinstance(answer, Answer) else answer.wait()


def _is_final_plan(data: dict[str, Any]) -> bool:
    return PlanStatus(str(data["status"])).is_final()


def start_plan(
    services: Services,
    model: CausalModel,
    mapping: Labelling | None,
    planner: str,
    time_limit: float,
    key: str | None = None,
    meanwhile: Callable[[], None] | None = None,
) -> Answer | PendingAnswer:
    """Return the kept plan of ``model`` (on ``mapping``'s object), or the one a worker is working on.

    ``key``: the request's answer key (``PlanInputs.key``), when the caller has it already.
    ``meanwhile``: work to do while a worker solves (see ``_start``). Blocks while no worker is free.
    """
    key = key or _key(services, "plan", model, mapping, planner, time_limit)
    args = (model, mapping, planner, time_limit, tuple(services.settings.catalog_folders))
    seconds = time_limit + services.settings.solve_grace_seconds
    return _start(services, key, worker.plan_job, args, seconds, _is_final_plan, meanwhile)


def plan(
    services: Services,
    model: CausalModel,
    mapping: Labelling | None,
    planner: str,
    time_limit: float,
) -> Answer:
    """Return the plan of ``model`` (on ``mapping``'s object), from the cache or a worker, waited for here."""
    return waited(start_plan(services, model, mapping, planner, time_limit))


def transfer(
    services: Services,
    model: CausalModel,
    mapping: Labelling,
    planner: str,
    time_limit: float,
    key: str | None = None,
) -> Answer:
    """Return the transfer verdict of ``model`` through ``mapping``, from the cache or a worker.

    ``key``: the request's answer key, when the caller has it already.
    """
    key = key or _key(services, "transfer", model, mapping, planner, time_limit)
    args = (model, mapping, planner, time_limit, tuple(services.settings.catalog_folders))
    seconds = time_limit + services.settings.solve_grace_seconds
    return waited(
        _start(
            services, key, worker.transfer_job, args, seconds, lambda data: data["verdict"] != Verdict.UNDECIDED.value
        )
    )


def simulate(
    services: Services,
    model: CausalModel,
    mapping: Labelling | None,
    planner: str,
    time_limit: float,
    picture: bool,
    key: str | None = None,
    meanwhile: Callable[[], None] | None = None,
) -> Answer:
    """Return the plan and its simulation report (and picture), from the cache or a worker.

    ``meanwhile``: work to do while a worker solves (see ``_start``).
    """
    key = key or _key(services, f"simulate:{picture}", model, mapping, planner, time_limit)
    args = (model, mapping, planner, time_limit, tuple(services.settings.catalog_folders), picture)
    seconds = time_limit + services.settings.solve_grace_seconds + SIMULATION_SECONDS
    return waited(
        _start(
            services,
            key,
            worker.simulate_job,
            args,
            seconds,
            lambda data: isinstance(data["planning"], dict) and _is_final_plan(data["planning"]),
            meanwhile,
        )
    )


def compiled_pddl(services: Services, model: CausalModel, mapping: Labelling | None) -> dict[str, str]:
    """Return the PDDL domain and problem of a plan request (pure and ~0.1 ms: done here, not by a worker)."""
    target = services.catalog.get((mapping or model.labelling).object_id)
    compiled = compile_task(build_task(model, target, mapping))
    return {"domain": compiled.domain, "problem": compiled.problem}


@dataclass(frozen=True)
class PlanInputs:
    """A plan-like request, read: its model (and the record to store), mapping, planner and time limit."""

    submission: ModelSubmission
    model: CausalModel
    mapping: Labelling | None
    mapping_report: Report | None
    planner: str
    time_limit: float
    model_text: str
    mapping_text: str
    catalog_key: str

    def key(self, kind: str) -> str:
        """Return the answer key of this request for answers of ``kind`` ('plan', 'simulate:True', ...)."""
        return answer_key(kind, self.model_text, self.mapping_text, self.planner, self.time_limit, self.catalog_key)

    @property
    def warnings(self) -> list[Diagnostic]:
        """Return the validation warnings of the model and the mapping."""
        return [*self.submission.report.warnings, *(self.mapping_report.warnings if self.mapping_report else [])]


def plan_inputs(body: PlanIn, services: Services, client: ClientIds) -> PlanInputs:
    """Read a plan-like request: its model, mapping, planner and time limit.

    An invalid model or mapping raises the 422 error (an inline model is stored first).
    """
    planner = resolve_planner(body.planner)
    time_limit = resolve_time_limit(body.time_limit, services.settings)
    submission = model_for_request(body.model, body.model_id, services, client)
    mapping_read = read_mapping(body.mapping, services)[0] if body.mapping is not None else None
    mapping_report = mapping_read.report if mapping_read is not None else None
    problem = invalid_input_error(submission, mapping_report)
    if problem is not None:
        if submission.is_new:
            save(services.engine, [submission.record])
        raise problem
    return _valid_inputs(submission, mapping_read, planner, time_limit, services)


def _valid_inputs(
    submission: ModelSubmission, mapping_read: MappingRead | None, planner: str, time_limit: float, services: Services
) -> PlanInputs:
    assert submission.model is not None and submission.canonical is not None
    mapping, mapping_text = None, canonical_text(None)
    if mapping_read is not None and mapping_read.canonical is not None:
        mapping, mapping_text = mapping_read.mapping, mapping_read.canonical
    return PlanInputs(
        submission,
        submission.model,
        mapping,
        mapping_read.report if mapping_read is not None else None,
        planner,
        time_limit,
        submission.canonical,
        mapping_text,
        services.catalog_key,
    )


def _kept_inputs(body: PlanIn | TransferIn, services: Services, client: ClientIds) -> PlanInputs | None:
    """Return a request's inputs from what was kept: an inline model and a mapping read before, both valid.

    None otherwise (a stored model is read from the database; a new document is read in a thread).
    """
    if body.model is None:
        return None
    model_read = services.reads.get(document_key("model", body.model)[0])
    if not isinstance(model_read, ModelRead) or model_read.canonical is None:
        return None
    mapping_read: MappingRead | None = None
    if body.mapping is not None:
        kept = services.reads.get(document_key("mapping", body.mapping)[0])
        if not isinstance(kept, MappingRead) or kept.canonical is None:
            return None
        mapping_read = kept
    planner = resolve_planner(body.planner)
    time_limit = resolve_time_limit(body.time_limit, services.settings)
    submission = _inline_submission(clean_json(body.model, "the model"), model_read, client)
    return _valid_inputs(submission, mapping_read, planner, time_limit, services)


def kept_answer(body: PlanIn, services: Services, client: ClientIds, kind: str) -> tuple[PlanInputs, Answer] | None:
    """Answer a plan-like request without waiting for anything, when it can be: its inputs and kept answer.

    It can be when the model is inline, it and the mapping were read before (their reads are
    kept) and are valid, the answer (``kind``: 'plan', 'simulate:True', ...) is kept, and the
    model's record is stored without waiting (``NoWaitWriter``: SQLite, write lock free).
    So the event loop can answer it itself, without a hop to a thread and back. None otherwise,
    with nothing stored: the request then goes the usual way, in a thread.
    """
    started = time.perf_counter()
    writer = services.no_wait_writer
    if writer is None:  # a database server: storing the record waits, so a thread answers
        return None
    inputs = _kept_inputs(body, services, client)
    if inputs is None:
        return None
    data = services.cache.get(inputs.key(kind))
    if data is None or not writer.save([inputs.submission.record]):
        return None
    return inputs, Answer(data, True, time.perf_counter() - started)


def kept_transfer(body: TransferIn, services: Services, client: ClientIds) -> tuple[Answer, TrialRecord] | None:
    """Answer a transfer request without waiting for anything, when it can be (as ``kept_answer``).

    Returns the answer and the trial, stored with its model (``trial.model_id``) without
    waiting; None otherwise, with nothing stored.
    """
    started = time.perf_counter()
    writer = services.no_wait_writer
    if writer is None:  # a database server: storing the record waits, so a thread answers
        return None
    inputs = _kept_inputs(body, services, client)
    if inputs is None:
        return None
    data = services.cache.get(inputs.key("transfer"))  # the key the transfer route computes
    if data is None:
        return None
    seconds = time.perf_counter() - started
    model = inputs.submission.record
    trial = new_trial_record(
        model.id, clean_json(body.mapping, "the mapping"), inputs.planner, data, True, seconds, client
    )
    if not writer.save([model, trial]):
        return None
    return Answer(data, True, seconds), trial
