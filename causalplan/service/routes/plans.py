"""POST /v1/plans: plan a model on its object, or on another object through a step-3 mapping."""

from __future__ import annotations

from fastapi import APIRouter

from causalplan.service import submissions
from causalplan.service.deps import ClientIdsDep, ServicesDep
from causalplan.service.responses import SafeJSONResponse
from causalplan.service.schemas import PlanIn, PlanOut, error_responses

router = APIRouter(prefix="/v1/plans", tags=["plans"], responses=error_responses(404, 429, 503, 504))


@router.post("", response_model=PlanOut, summary="Plan a model")
def create_plan(body: PlanIn, services: ServicesDep, client: ClientIdsDep) -> SafeJSONResponse:
    """Plan how to assemble the object so the model's goal holds, and replay the plan on it.

    The same JSON as `causalplan plan --json`, plus `cached` (an identical request was
    answered before) and `model_id`. An inline model is stored, valid or not. An invalid
    model or mapping is answered with 422 and the CLI's codes.
    """
    # One hop to a worker thread per request (~0.2 ms each, on a path that answers a repeat in
    # ~1 ms): the dependencies are `async def`, no SessionDep (its start and its end would each
    # hop; a stored model's session is opened where it is read), and the response is checked
    # here and sent as it is (FastAPI would hop again to check a returned model).
    inputs = submissions.plan_inputs(body, services, client)
    key = inputs.key("plan")
    # An inline model's record is stored while the worker solves (the two take ~0.16 ms and
    # ~8 ms), or at once for a kept answer; a request refused before a worker took it stores nothing.
    store = submissions.storing(services, inputs.submission)
    answer = submissions.plan(services, inputs.model, inputs.mapping, inputs.planner, inputs.time_limit, key, store)
    data = dict(answer.data)
    if body.include_pddl:
        data["pddl"] = submissions.compiled_pddl(services, inputs.model, inputs.mapping)
    response = PlanOut.model_validate(
        {
            **data,
            "planner_requested": body.planner,
            "cached": answer.cached,
            "model_id": inputs.submission.record.id,
            "warnings": [warning.as_dict() for warning in inputs.warnings],
        }
    )
    return SafeJSONResponse(response.model_dump(mode="json"))
