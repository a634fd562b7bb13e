"""POST /v1/explanations: plan a model and explain the plan (why this step; why not another)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from causalplan.service.api.schemas.common import error_responses
from causalplan.service.api.schemas.explanations import ExplanationIn, ExplanationOut
from causalplan.service.deps import ClientIdsDep, ServicesDep
from causalplan.service.documents import StrictJSONRoute, plan_inputs
from causalplan.service.work.planning import ExplanationArguments
from causalplan.service.work.registry import EXPLANATION

router = APIRouter(
    prefix="/v1/explanations",
    tags=["explanations"],
    responses=error_responses(403, 404, 429, 503, 504),
    route_class=StrictJSONRoute,
)


@router.post("", response_model=ExplanationOut, response_model_exclude_unset=True, summary="Explain a plan")
def create_explanation(body: ExplanationIn, services: ServicesDep, client: ClientIdsDep) -> dict[str, Any]:
    """Plan the model, then say why a step is there (`why`) and why not another plan (`why_not`).

    The same JSON as `causalplan explain --json`, plus `model_id`. A why-not question is
    answered by planning again with its constraint compiled into the PDDL; the alternative
    plan is replayed (and checked by VAL with `validate`) like any plan. A question the plan
    or the object cannot answer (a part it does not have: `unknown_part`; `invalid_question`,
    `unknown_fit`, `unknown_step`) or a model without a plan (`no_plan_to_explain`) is a 422.
    """
    inputs = plan_inputs(body, services, client)
    inputs.store(services)
    arguments = ExplanationArguments(
        inputs.model,
        inputs.mapping,
        inputs.planner,
        inputs.time_limit,
        body.why,
        body.why_not,
        body.validate_plan,
        body.simulate,
    )
    data = services.work.run(EXPLANATION, arguments)
    return {**data, "model_id": inputs.submission.record.id}
