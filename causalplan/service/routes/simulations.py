"""POST /v1/simulations: plan a model and run the plan in the headless physics simulator."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter
from pydantic import Field

from causalplan.service import submissions
from causalplan.service.deps import ClientIdsDep, ServicesDep
from causalplan.service.schemas import PlanIn, error_responses

router = APIRouter(prefix="/v1/simulations", tags=["simulations"], responses=error_responses(404, 429, 503, 504))


class SimulationIn(PlanIn):
    """POST /v1/simulations: what POST /v1/plans takes, and whether to draw the final assembly."""

    picture: bool = Field(default=True, description="Also return a PNG of the final assembly as a data URL.")


@router.post("", summary="Plan a model and simulate the plan")
def create_simulation(body: SimulationIn, services: ServicesDep, client: ClientIdsDep) -> dict[str, Any]:
    """Plan as POST /v1/plans does, then run the plan in headless PyBullet and check every step.

    Returns `planning` (the plan request's JSON), `simulation` (per-step checks with measured
    figures, stability, the true mechanism on the simulated assembly, `produces_goal`) and
    `image` (a PNG data URL of the final assembly, when `picture` is true), plus `cached`.
    """
    inputs = submissions.plan_inputs(body, services, client)
    key = inputs.key(f"simulate:{body.picture}")
    store = submissions.storing(services, inputs.submission)
    answer = submissions.simulate(
        services, inputs.model, inputs.mapping, inputs.planner, inputs.time_limit, body.picture, key, store
    )
    return {**answer.data, "cached": answer.cached, "model_id": str(inputs.submission.record.id)}
