"""POST /v1/plans: plan a model on its object, or on another object through a step-3 mapping."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from causalplan.causal.model import CausalModel, Labelling
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import catalog_task
from causalplan.pddl.writer import compile_task
from causalplan.service.api.schemas.common import error_responses
from causalplan.service.api.schemas.plans import PlanIn, PlanOut
from causalplan.service.deps import ClientIdsDep, ServicesDep
from causalplan.service.documents import StrictJSONRoute, plan_inputs
from causalplan.service.work.planning import PlanArguments
from causalplan.service.work.registry import PLAN

router = APIRouter(
    prefix="/v1/plans",
    tags=["plans"],
    responses=error_responses(403, 404, 429, 503, 504),
    route_class=StrictJSONRoute,
)


@router.post("", response_model=PlanOut, response_model_exclude_unset=True, summary="Plan a model")
def create_plan(body: PlanIn, services: ServicesDep, client: ClientIdsDep) -> dict[str, Any]:
    """Plan how to assemble the object so the model's goal holds, and replay the plan on it.

    The same JSON as `causalplan plan --json`, plus `cached` (an identical request was
    answered before) and `model_id`. An inline model is stored, valid or not. An invalid
    model or mapping is answered with 422 and the CLI's codes.
    """
    inputs = plan_inputs(body, services, client)
    arguments = PlanArguments(inputs.model, inputs.mapping, inputs.planner, inputs.time_limit, body.validate_plan)
    answer = services.work.answer(PLAN, arguments, lambda: inputs.store(services))
    pddl = compiled_pddl(services.catalog, inputs.model, inputs.mapping) if body.include_pddl else None
    return {
        **answer.data,
        "pddl": pddl,
        "planner_requested": body.planner,
        "cached": answer.cached,
        "model_id": inputs.submission.record.id,
        "warnings": [warning.as_dict() for warning in inputs.warnings],
    }


def compiled_pddl(catalog: Catalog, model: CausalModel, mapping: Labelling | None) -> dict[str, str]:
    """Return the readable PDDL domain and problem of a plan request (pure and quick: done here, not by a worker)."""
    compiled = compile_task(catalog_task(model, catalog, mapping))
    return {"domain": compiled.domain, "problem": compiled.problem}
