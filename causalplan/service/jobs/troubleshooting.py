"""The ``troubleshooting`` kind of job: the Franka Panda carries out a troubleshooting episode in physics.

``POST /v1/troubleshooting`` with ``robot: true`` (or ``POST /v1/jobs`` with ``kind:
"troubleshooting"``) queues it. When it is posted, the model is stored and the table is
solved by the interactive work (``TROUBLESHOOTING``, kept in the answer cache), so a bad
fault, object or mapping is refused at once (422/404) and nothing is queued; the runner then
has the robot carry out the episode in a worker of the jobs' pool (``QUEUED_TROUBLESHOOTING``).
The 3D player's document of the run (``sim.robot_episode_playback``) is stored with the job as
its file, and served at ``playback_url`` (``GET /v1/jobs/{id}/playback``) until the job expires.
``troubleshooting_inputs`` reads a request's model and mapping the same way for the route.
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from causalplan.service.errors import InvalidRequestError
from causalplan.service.jobs.requests import TroubleshootingRequest
from causalplan.service.jobs.work import JobFile, Outcome, Progress, in_pool
from causalplan.service.work.registry import QUEUED_TROUBLESHOOTING, TROUBLESHOOTING
from causalplan.service.work.troubleshooting import TroubleshootingArguments

PLAYBACK_TYPE = "application/json"
"""The media type of a troubleshooting job's file: the 3D player's document."""

if TYPE_CHECKING:
    from causalplan.service.api.schemas.jobs import TroubleshootingJobIn
    from causalplan.service.api.schemas.troubleshooting import TroubleshootingIn
    from causalplan.service.deps import Services
    from causalplan.service.documents import ModelSubmission
    from causalplan.service.storage.crud import ClientIds


@dataclass(frozen=True)
class TroubleshootingInputs:
    """A request's model (stored when it came inline), its mapping's warnings, and the work's arguments."""

    submission: ModelSubmission
    arguments: TroubleshootingArguments
    warnings: list[dict[str, Any]]


def troubleshooting_inputs(
    body: TroubleshootingIn, services: Services, client: ClientIds, robot: bool = False
) -> TroubleshootingInputs:
    """Read the request's model and mapping; store an inline model (valid or not); raise 422 when either is invalid."""
    from causalplan.service.documents import invalid_input_error, model_for_request, read_mapping
    from causalplan.service.storage.crud import save

    submission = model_for_request(body.model, body.model_id, services, client)
    mapping = read_mapping(body.mapping, services) if body.mapping is not None else None
    if submission.is_new:
        save(services.engine, [submission.record])
    problem = invalid_input_error(submission, mapping.report if mapping is not None else None)
    if problem is not None:
        raise problem
    assert submission.model is not None
    labelling = mapping.mapping if mapping is not None else None
    arguments = TroubleshootingArguments(
        submission.model, labelling, body.object, body.fault, body.strategy, robot, robot and body.motors
    )
    warnings = [*submission.report.warnings, *(mapping.report.warnings if mapping is not None else [])]
    return TroubleshootingInputs(submission, arguments, [warning.as_dict() for warning in warnings])


def playback_url(job_id: object) -> str:
    """Return where the API serves the 3D player's document of troubleshooting job ``job_id``."""
    return f"/v1/jobs/{job_id}/playback"


def prepare_troubleshooting(body: TroubleshootingJobIn, services: Services) -> TroubleshootingRequest:
    from causalplan.service.storage.crud import ClientIds

    if body.fault is None:
        raise InvalidRequestError(
            "The robot carries out one episode: name the broken part ('fault').", details={"field": "fault"}
        )
    inputs = troubleshooting_inputs(body, services, ClientIds())
    services.work.answer(TROUBLESHOOTING, inputs.arguments)  # a bad fault or object: refused now, nothing queued
    return TroubleshootingRequest(
        model_id=str(inputs.submission.record.id),
        mapping=body.mapping,
        object=body.object,
        fault=body.fault,
        strategy=body.strategy,
        motors=body.motors,
    )


def run_troubleshooting_job(request: TroubleshootingRequest, services: Services, progress: Progress) -> Outcome:
    """Have the robot carry out the episode: ``TroubleshootingRobotOut``, with the player's document as the file."""
    from causalplan.service.api.schemas.troubleshooting import TroubleshootingIn
    from causalplan.service.storage.crud import ClientIds

    body = TroubleshootingIn.model_validate(
        {
            "model_id": request.model_id,
            "mapping": request.mapping,
            "object": request.object,
            "fault": request.fault,
            "strategy": request.strategy,
            "robot": True,
            "motors": request.motors,
        }
    )
    inputs = troubleshooting_inputs(body, services, ClientIds(), robot=True)
    progress(0, 1)
    data = in_pool(services, progress, QUEUED_TROUBLESHOOTING, inputs.arguments)
    progress(1, 1)
    document = data.pop("playback", None)
    result = {**data, "model_id": str(uuid.UUID(request.model_id))}
    if not isinstance(document, bytes):
        return Outcome({**result, "playback": None})
    # The URL is the route's to say (``playback_url``, filled in when the job is read).
    described = {"url": None, "content_type": PLAYBACK_TYPE, "bytes": len(document)}
    return Outcome({**result, "playback": described}, JobFile(document, PLAYBACK_TYPE))
