"""POST /v1/simulations: plan a model and run the plan in the headless physics simulator; a robot run is a job.

A run of the robot (and its film) takes tens of seconds to minutes, so it is long work: it is
queued in the jobs table and done by a job runner in the jobs' own workers, never in the
workers that answer plans, transfers and checks. Its request is answered with 202 and the
job, as POST /v1/jobs answers (the same body works: clients follow the job's ``url``).
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request, Response

from causalplan.service.api.routes.jobs import job_out, job_url, queue_job
from causalplan.service.api.schemas.common import JOB_CLIENT_RESPONSES, JOB_LIMIT_RESPONSE, error_responses
from causalplan.service.api.schemas.jobs import JobOut, SimulationJobIn, VideoJobIn
from causalplan.service.api.schemas.plans import SimulationIn
from causalplan.service.api.schemas.simulations import SimulationOut
from causalplan.service.deps import ClientIdsDep, Services, ServicesDep
from causalplan.service.documents import StrictJSONRoute, plan_inputs
from causalplan.service.owners import BearerDep, JobOwner, resolve_owner
from causalplan.service.storage.jobs import JobKind
from causalplan.service.storage.records import JobRecord
from causalplan.service.work.planning import SimulationArguments
from causalplan.service.work.registry import SIMULATION

router = APIRouter(
    prefix="/v1/simulations",
    tags=["simulations"],
    responses=error_responses(403, 404, 429, 503, 504),
    route_class=StrictJSONRoute,
)

_TOO_MUCH = {**JOB_LIMIT_RESPONSE, "description": f"Every planner worker is busy. {JOB_LIMIT_RESPONSE['description']}"}
"""The 429 of a simulation: the planner workers' queue, or a robot run's job over a limit."""
_ONLY_PLANNED = ("picture", "robot", "include_pddl", "motors")
"""What a robot run's job does not take of a simulation's body (it films, or reports, the robot)."""


def queue_robot_run(body: SimulationIn, services: Services, owner: JobOwner) -> JobRecord:
    """Queue the robot's run of ``body`` as ``owner``'s job: a ``video`` job when filmed, else a ``simulation`` job."""
    request: dict[str, Any] = body.model_dump(by_alias=True, exclude_unset=True)
    if body.video is not None:
        request = {key: value for key, value in request.items() if key not in _ONLY_PLANNED}
        return queue_job(VideoJobIn.model_validate({**request, "kind": JobKind.VIDEO.value}), services, owner)
    request = {key: value for key, value in request.items() if key != "video"} | {"picture": False}
    return queue_job(SimulationJobIn.model_validate({**request, "kind": JobKind.SIMULATION.value}), services, owner)


@router.post(
    "",
    summary="Plan a model and simulate the plan (with the robot: a job, answered 202)",
    response_model=None,  # two answers: declared below, each with its model
    responses={
        200: {"model": SimulationOut, "description": "The plan, the simulator's report of it and the picture."},
        202: {
            "model": JobOut,
            "description": "With `robot`: the robot's run (and film) is queued as a job; follow `url` "
            "(also in `Location`) as for POST /v1/jobs.",
        },
        401: JOB_CLIENT_RESPONSES[401],
        429: _TOO_MUCH,
    },
)
def create_simulation(
    body: SimulationIn,
    services: ServicesDep,
    client: ClientIdsDep,
    request: Request,
    credentials: BearerDep,
    response: Response,
) -> dict[str, Any]:
    """Plan as POST /v1/plans does, then run the plan in headless PyBullet and check every step.

    Returns `planning` (the plan request's JSON), `simulation` (per-step checks with measured
    figures, stability, the true mechanism on the simulated assembly, `produces_goal`) and
    `image` (a PNG data URL of the final assembly, when `picture` is true), plus `cached`.

    With `robot: true` the Franka Panda carries out the plan, which takes up to the server's
    `robot_seconds` (GET /health, `limits`): that is long work, so the answer is **202 with a
    job** (as POST /v1/jobs answers; its `url` is also in `Location`), and the plan requests of
    others never wait for it. The job's `result`, once it has `succeeded`, is this route's
    answer with the robot: each step of `simulation` says what the robot did (`robot`:
    transit, grasp, carry, ...), and `robot` says whether it carried out the plan
    (`{"carried_out": false, "reason": {"code": "robot_cannot_execute", "step": N, "failure":
    ..., "message"}}`). With `video: "mp4"` or `"gif"` the job is a `video` job: its result's
    `video` is `{"url", "content_type", "bytes"}`, the film at `/v1/jobs/{id}/video`. The job is
    the client's, under its limits, as for POST /v1/jobs (its bearer token: an API key or the
    research token; else its address).
    """
    if body.robot:
        record = queue_robot_run(body, services, resolve_owner(request, services, credentials))
        response.status_code = 202
        response.headers["Location"] = job_url(record.id)
        job: dict[str, Any] = job_out(record).model_dump(mode="json")
        return job
    inputs = plan_inputs(body, services, client)
    arguments = SimulationArguments(
        inputs.model, inputs.mapping, inputs.planner, inputs.time_limit, body.picture, val=body.validate_plan
    )
    answer = services.work.answer(SIMULATION, arguments, lambda: inputs.store(services))
    return {**answer.data, "cached": answer.cached, "model_id": str(inputs.submission.record.id)}
