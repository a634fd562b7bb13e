"""POST /v1/plans: plan a model on its object, or on another object through a step-3 mapping."""

from __future__ import annotations

from fastapi import APIRouter

from causalplan.service import crud, submissions
from causalplan.service.deps import ClientIdsDep, ServicesDep, SessionDep
from causalplan.service.schemas import PlanIn, PlanOut, error_responses

router = APIRouter(prefix="/v1/plans", tags=["plans"], responses=error_responses(404, 429, 503, 504))


@router.post("", response_model=PlanOut, summary="Plan a model")
def create_plan(body: PlanIn, services: ServicesDep, session: SessionDep, client: ClientIdsDep) -> PlanOut:
    """Plan how to assemble the object so the model's goal holds, and replay the plan on it.

    The same JSON as `causalplan plan --json`, plus `cached` (an identical request was
    answered before) and `model_id`. An inline model is stored, valid or not. An invalid
    model or mapping is answered with 422 and the CLI's codes.
    """
    submission, mapping, mapping_report, planner, time_limit = submissions.plan_inputs(body, services, session, client)
    assert submission.model is not None
    answer = submissions.plan(services, submission.model, mapping, planner, time_limit)
    if submission.is_new:
        crud.save(session, [submission.record])
    data = dict(answer.data)
    if not body.include_pddl:
        data.pop("pddl", None)
    warnings = [*submission.report.warnings, *(mapping_report.warnings if mapping_report else [])]
    return PlanOut.model_validate(
        {
            **data,
            "planner_requested": body.planner,
            "cached": answer.cached,
            "model_id": submission.record.id,
            "warnings": [warning.as_dict() for warning in warnings],
        }
    )
