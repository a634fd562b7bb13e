"""POST /v1/troubleshooting: repair a broken object with a person's causal model, beside the baselines.

The exact solve runs in a worker of the interactive pool (``TROUBLESHOOTING`` in the work
registry; its answers are kept), never on the request's thread. With ``robot`` the Franka
Panda carries out the episode in physics, which takes seconds to minutes: that is a job
(``service.jobs.troubleshooting``), answered 202 as POST /v1/simulations answers a robot run.
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request, Response

from causalplan.service.api.routes.jobs import job_out, job_url, queue_job
from causalplan.service.api.schemas.common import JOB_CLIENT_RESPONSES, JOB_LIMIT_RESPONSE, error_responses
from causalplan.service.api.schemas.jobs import JobOut, TroubleshootingJobIn
from causalplan.service.api.schemas.troubleshooting import TroubleshootingIn, TroubleshootingOut
from causalplan.service.deps import ClientIdsDep, ServicesDep
from causalplan.service.documents import StrictJSONRoute
from causalplan.service.jobs.troubleshooting import troubleshooting_inputs
from causalplan.service.owners import BearerDep, resolve_owner
from causalplan.service.storage.jobs import JobKind
from causalplan.service.work.registry import TROUBLESHOOTING

router = APIRouter(
    prefix="/v1/troubleshooting",
    tags=["troubleshooting"],
    responses=error_responses(403, 404, 429, 503, 504),
    route_class=StrictJSONRoute,
)


@router.post(
    "",
    summary="Troubleshoot a broken object (with the robot: a job, answered 202)",
    response_model=None,  # two answers: declared below, each with its model
    responses={
        200: {"model": TroubleshootingOut, "description": "The strategies' table, and the episode of `fault`."},
        202: {
            "model": JobOut,
            "description": "With `robot`: the robot's run of the episode is queued as a job; follow `url` "
            "(also in `Location`) as for POST /v1/jobs. Its result is `TroubleshootingRobotOut`.",
        },
        401: JOB_CLIENT_RESPONSES[401],
        429: {**JOB_LIMIT_RESPONSE, "description": f"Every worker is busy. {JOB_LIMIT_RESPONSE['description']}"},
    },
)
def create_troubleshooting(
    body: TroubleshootingIn,
    services: ServicesDep,
    client: ClientIdsDep,
    request: Request,
    credentials: BearerDep,
    response: Response,
) -> dict[str, Any]:
    """Solve the model's, uniform's and the oracle's exact policies on the broken object, and score them.

    Solved in a worker (a catalog object takes milliseconds), within a bound on the solver's
    states (`troubleshooting_too_large` beyond it); the same request's answer is kept.

    The same JSON as `causalplan troubleshoot --all-faults --json`, with `episode` (as
    `--fault PART --json`) when `fault` is given, and `model_id`. An inline model is stored,
    valid or not. Bad input is 422 with a code: `unknown_fault_part`, `fault_not_needed`,
    `object_without_faults`, `mapping_does_not_fit`, `troubleshooting_too_large`, or the
    model's and mapping's validation codes; an unknown object is 404.

    With `robot: true` (and `fault`) the Franka Panda carries out the episode in physics, action
    by action (detach, set aside, take the spare, attach, the test's light): the answer is
    **202 with a job** (as POST /v1/jobs answers; its `url` is also in `Location`). Its
    `result`, once `succeeded`, is `TroubleshootingRobotOut`: this answer with `robot` (each
    action's motions and what its test showed in physics, `produces_goal`). What is wrong with
    the request is refused at once (422/404), and nothing is queued.
    """
    if body.robot:
        job = TroubleshootingJobIn.model_validate(
            {**body.model_dump(by_alias=True, exclude_unset=True), "kind": JobKind.TROUBLESHOOTING.value}
        )
        record = queue_job(job, services, resolve_owner(request, services, credentials))
        response.status_code = 202
        response.headers["Location"] = job_url(record.id)
        queued: dict[str, Any] = job_out(record).model_dump(mode="json")
        return queued
    inputs = troubleshooting_inputs(body, services, client)
    answer = services.work.answer(TROUBLESHOOTING, inputs.arguments)
    return {**answer.data, "model_id": inputs.submission.record.id, "warnings": inputs.warnings}
