"""The service's errors: children of ``CausalPlanError``, each with its HTTP status.

Routes raise these (or let lower packages' errors through); ``http_status`` and the one
handler in ``main`` turn every one of them into ``{"error": {"code", "message", "details"}}``.
"""

from __future__ import annotations

from causalplan.errors import CatalogError, CausalPlanError, InputFileError, PlannerUnavailableError, UnknownObjectError
from causalplan.explain.contrast import PlanUnavailableError
from causalplan.explain.questions import QuestionError
from causalplan.limits import LimitExceededError
from causalplan.studies.errors import (
    InvalidExperimentError,
    InvalidRecruitmentError,
    PlatformIdRequiredError,
    StepLockedError,
)
from causalplan.troubleshoot.errors import TroubleshootError


class ServiceError(CausalPlanError):
    """An error of the HTTP service; ``status_code`` is its HTTP status, ``headers`` go with it."""

    code = "service_error"
    status_code = 500

    def __init__(
        self, message: str, *, details: dict[str, object] | None = None, headers: dict[str, str] | None = None
    ) -> None:
        super().__init__(message, details=details)
        self.headers = headers or {}


class InvalidRequestError(ServiceError):
    """The request is malformed: not JSON, wrong field types, or fields that contradict each other."""

    code = "invalid_request"
    status_code = 422


class InvalidModelError(ServiceError):
    """The causal model did not validate; ``details`` holds the report with the CLI's codes."""

    code = "invalid_model"
    status_code = 422


class InvalidMappingError(ServiceError):
    """The step-3 mapping did not validate; ``details`` holds the report with the CLI's codes."""

    code = "invalid_mapping"
    status_code = 422


class BodyTooLargeError(ServiceError):
    """The request body is larger than ``max_body_bytes``."""

    code = "body_too_large"
    status_code = 413


class NotFoundError(ServiceError):
    """A stored record or a route does not exist."""

    code = "not_found"
    status_code = 404


class FilmNotFoundError(NotFoundError):
    """No film of the robot is made under this key or job (never, not yet, or it has expired)."""

    code = "video_not_found"


class PlaybackNotFoundError(NotFoundError):
    """The job has no 3D player's document: not a troubleshooting job, or it ended without one."""

    code = "playback_not_found"


class ModelNotFoundError(NotFoundError):
    """No stored model has this id."""

    code = "model_not_found"


class NotAuthenticatedError(ServiceError):
    """A research endpoint was called without the right bearer token."""

    code = "not_authenticated"
    status_code = 401

    def __init__(self, message: str) -> None:
        super().__init__(message, headers={"WWW-Authenticate": "Bearer"})


class ResearchDisabledError(ServiceError):
    """The research endpoints are off because no token is configured."""

    code = "research_disabled"
    status_code = 403


class TryLaterError(ServiceError):
    """Too much at once (429); ``retry_after``, in the details and as ``Retry-After``, says when to try again.

    Only its children, each with its own code, are raised.
    """

    status_code = 429

    def __init__(self, message: str, retry_after: int) -> None:
        super().__init__(message, details={"retry_after": retry_after}, headers={"Retry-After": str(retry_after)})
        self.retry_after = retry_after


class QueueFullError(TryLaterError):
    """Every planner worker is busy and the queue is full."""

    code = "queue_full"


class TooManyRequestsInFlightError(TryLaterError):
    """One client has as many interactive planner requests running or waiting as it may (``service.fair_share``)."""

    code = "too_many_requests_in_flight"


class TooManyAttemptsError(TryLaterError):
    """Too many wrong research tokens came from this client address."""

    code = "too_many_attempts"


class JobNotFoundError(NotFoundError):
    """No job has this id (or its result has expired)."""

    code = "job_not_found"


class JobNotFinishedError(ServiceError):
    """The job is queued or running: what it makes is not there yet (ask again once it has succeeded)."""

    code = "job_not_finished"
    status_code = 409


class JobFinishedError(ServiceError):
    """The job has finished already, so it cannot be cancelled."""

    code = "job_finished"
    status_code = 409


class TooManyJobsError(TryLaterError):
    """The service holds as many unfinished jobs as it takes."""

    code = "too_many_jobs"


class TooManyJobsInFlightError(TryLaterError):
    """One client has as many queued or running jobs as it may."""

    code = "too_many_jobs_in_flight"


class JobStorageFullError(TryLaterError):
    """One client's stored jobs (requests and results, until they expire) hold as many bytes as it may."""

    code = "job_storage_full"


class StorageFullError(TryLaterError):
    """One client's stored models, trials and jobs hold as many bytes as its allowance (``storage.allowance``)."""

    code = "storage_full"


class TooManyJobStartsError(TryLaterError):
    """One client posted more jobs this minute than it may."""

    code = "too_many_job_starts"


class PlanningTimeoutError(ServiceError):
    """A worker was still busy well after the solve's time limit, so it was killed."""

    code = "planning_timeout"
    status_code = 504


class WorkerCrashedError(ServiceError):
    """The worker running this solve died (killed, out of memory, or crashed); it has been replaced."""

    code = "planner_crashed"
    status_code = 503

    def __init__(self, message: str, *, details: dict[str, object] | None = None) -> None:
        super().__init__(message, details=details, headers={"Retry-After": "1"})


class WorkerDiedError(WorkerCrashedError):
    """The worker process died under the work (killed, out of memory, crashed); ``details`` has its ``exit_code``.

    Not a closed pool (the server stopping) nor a call no worker could take: a job's work is
    run once more only after this one.
    """


class NotReadyError(ServiceError):
    """This replica's planner pool has not answered its first plan yet (``GET /health/ready``)."""

    code = "not_ready"
    status_code = 503

    def __init__(self, message: str) -> None:
        super().__init__(message, headers={"Retry-After": "1"})


class PlannerOutOfMemoryError(ServiceError):
    """The planner worker itself ran out of memory (its limit is ``worker_memory_mb``)."""

    code = "planner_out_of_memory"
    status_code = 503


class StorageError(ServiceError):
    """The database could not be read or written; nothing of the request was stored."""

    code = "storage_unavailable"
    status_code = 503


class MethodNotAllowedError(ServiceError):
    """The route exists, but not for this HTTP method."""

    code = "method_not_allowed"
    status_code = 405


class InternalError(ServiceError):
    """A bug: something failed that should not; the log has the traceback, the client does not."""

    code = "internal_error"
    status_code = 500


# -- the participant and research pages (rendered as an HTML page there, see ``pages.templating``) --


class ParticipantNotFoundError(NotFoundError):
    """No participant has this link code."""

    code = "participant_not_found"


class ExperimentNotFoundError(NotFoundError):
    """No experiment has this id."""

    code = "experiment_not_found"


class InvalidFormError(InvalidRequestError):
    """A submitted form is malformed (a field missing, repeated, too long, or not one of the choices)."""

    code = "invalid_form"


class LoginRequiredError(ServiceError):
    """A research page was opened without the research token (cookie or bearer)."""

    code = "login_required"
    status_code = 401


class CrossSiteRequestError(ServiceError):
    """A research form was posted from another site (its Origin is not this server)."""

    code = "cross_site_request"
    status_code = 403


class ParticipantIdReservedError(ServiceError):
    """A client named a study participant (or their pages' session) as itself: only their own pages may."""

    code = "participant_id_reserved"
    status_code = 403


class TooManyDemoStartsError(TryLaterError):
    """One client started more demo participants this minute than the service allows."""

    code = "too_many_demo_starts"


class TooManyModelsError(TryLaterError):
    """One client stored more models with POST /v1/models this minute than the service allows."""

    code = "too_many_models"


class TooManyArrivalsError(TryLaterError):
    """One client arrived on public study links more often this minute than the service allows."""

    code = "too_many_arrivals"


class ClientHoldsPlacesError(TryLaterError):
    """One client address already holds its ``places_per_client`` places admitted but not started."""

    code = "client_holds_places"


_STATUS_BY_CODE = {
    "unknown_planner": 422,
    "plan_rejected_by_val": 500,  # our compilation and VAL disagree: a fault of ours, with VAL's words
    "validator_error": 503,
}
"""Errors of lower packages this module does not import (the planners'), by their stable code."""

_LOWER_STATUS: dict[type[CausalPlanError], int] = {
    UnknownObjectError: 404,
    InputFileError: 422,
    PlannerUnavailableError: 503,
    CatalogError: 500,
    LimitExceededError: 422,
    InvalidExperimentError: 422,
    InvalidRecruitmentError: 422,
    StepLockedError: 409,
    PlatformIdRequiredError: 403,
    QuestionError: 422,  # a why-not question the plan or the object cannot answer (unknown_part, ...)
    PlanUnavailableError: 422,  # a model without a plan to explain
    TroubleshootError: 422,  # a fault the object cannot have, an object without faults, a mapping that does not fit
}


def http_status(exc: CausalPlanError) -> int:
    """Return the HTTP status of any causalplan error (500 for ones no table knows)."""
    if isinstance(exc, ServiceError):
        return exc.status_code
    if exc.code in _STATUS_BY_CODE:
        return _STATUS_BY_CODE[exc.code]
    for cls in type(exc).__mro__:
        if cls in _LOWER_STATUS:
            return _LOWER_STATUS[cls]
    return 500


def error_body(code: str, message: str, details: dict[str, object] | None = None) -> dict[str, object]:
    """Return the one error shape: ``{"error": {"code", "message", "details"}}``."""
    return {"error": {"code": code, "message": message, "details": details or {}}}


def error_class(code: str) -> type[CausalPlanError]:
    """Return the ``CausalPlanError`` subclass with this ``code`` (the root when none has it)."""
    pending: list[type[CausalPlanError]] = [CausalPlanError]
    while pending:
        cls = pending.pop()
        if cls.code == code:
            return cls
        pending.extend(cls.__subclasses__())
    return CausalPlanError
