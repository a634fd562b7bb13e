"""POST /v1/simulations: plan a model and run the plan in the headless physics simulator."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from causalplan.service.deps import ClientIdsDep, ServicesDep
from causalplan.service.documents import StrictJSONRoute, plan_inputs
from causalplan.service.schemas.common import error_responses
from causalplan.service.schemas.plans import SimulationIn

router = APIRouter(
    prefix="/v1/simulations",
    tags=["simulations"],
    responses=error_responses(404, 429, 503, 504),
    route_class=StrictJSONRoute,
)


@router.post("", summary="Plan a model and simulate the plan")
def create_simulation(body: SimulationIn, services: ServicesDep, client: ClientIdsDep) -> dict[str, Any]:
    """Plan as POST /v1/plans does, then run the plan in headless PyBullet and check every step.

    Returns `planning` (the plan request's JSON), `simulation` (per-step checks with measured
    figures, stability, the true mechanism on the simulated assembly, `produces_goal`) and
    `image` (a PNG data URL of the final assembly, when `picture` is true), plus `cached`.
    """
    inputs = plan_inputs(body, services, client)
    answer = services.answers.simulate(
        inputs.model,
        inputs.mapping,
        inputs.planner,
        inputs.time_limit,
        body.picture,
        lambda: inputs.store(services),
    )
    return {**answer.data, "cached": answer.cached, "model_id": str(inputs.submission.record.id)}
