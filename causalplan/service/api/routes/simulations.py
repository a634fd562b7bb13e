"""POST /v1/simulations: plan a model and run the plan in the headless physics simulator (or by the robot).

GET /v1/simulations/videos/{key}: a film of the robot that a simulation with ``video`` made.
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path, Response

from causalplan.service.api.schemas.common import error_responses
from causalplan.service.api.schemas.plans import SimulationIn
from causalplan.service.deps import ClientIdsDep, ServicesDep
from causalplan.service.documents import StrictJSONRoute, plan_inputs
from causalplan.service.films import FilmNotFoundError

router = APIRouter(
    prefix="/v1/simulations",
    tags=["simulations"],
    responses=error_responses(403, 404, 429, 503, 504),
    route_class=StrictJSONRoute,
)

VIDEO_KEY = r"^[0-9a-f]{32}$"


@router.post("", summary="Plan a model and simulate the plan (or have the robot carry it out, and film it)")
def create_simulation(body: SimulationIn, services: ServicesDep, client: ClientIdsDep) -> dict[str, Any]:
    """Plan as POST /v1/plans does, then run the plan in headless PyBullet and check every step.

    Returns `planning` (the plan request's JSON), `simulation` (per-step checks with measured
    figures, stability, the true mechanism on the simulated assembly, `produces_goal`) and
    `image` (a PNG data URL of the final assembly, when `picture` is true), plus `cached`.

    With `robot: true` the Franka Panda carries out the plan: each step of `simulation` says
    what the robot did (`robot`: transit, grasp, carry, ...), `simulation.trajectory` sums up
    its motions, and `robot` says whether it carried out the plan: `{"carried_out": false,
    "reason": {"code": "robot_cannot_execute", "step": N, "failure": "unreachable" |
    "no_collision_free_path" | "collision" | "grasp_lost" | a simulator code, "message"}}`.
    With `video: "mp4"` or `"gif"` it is filmed too, and `video` is `{"key", "url",
    "content_type", "bytes"}`: fetch the film at `url` while the server keeps it. A robot run
    may take the server's `robot_seconds` (GET /health, `limits`) beyond the planner's limit.
    """
    inputs = plan_inputs(body, services, client)
    if body.robot:
        answer = services.answers.robot_simulation(
            inputs.model,
            inputs.mapping,
            inputs.planner,
            inputs.time_limit,
            body.video,
            services.films,
            lambda: inputs.store(services),
        )
    else:
        answer = services.answers.simulate(
            inputs.model,
            inputs.mapping,
            inputs.planner,
            inputs.time_limit,
            body.picture,
            lambda: inputs.store(services),
        )
    return {**answer.data, "cached": answer.cached, "model_id": str(inputs.submission.record.id)}


@router.get(
    "/videos/{key}",
    summary="A film of the robot carrying out a plan (MP4 or GIF)",
    response_class=Response,
    responses={200: {"content": {"video/mp4": {}, "image/gif": {}}, "description": "The film."}},
)
def get_video(
    key: Annotated[str, Path(pattern=VIDEO_KEY, description="The key from a simulation's `video`.")],
    services: ServicesDep,
) -> Response:
    """Return the film kept under `key` (404 `video_not_found` when it is not, or not yet, made)."""
    film = services.films.get(key)
    if film.state != "ready":
        raise FilmNotFoundError(
            f"The video '{key}' is {film.state}, not ready.", details={"key": key, "state": film.state}
        )
    return Response(
        film.data,
        media_type=film.content_type,
        headers={"Cache-Control": "private, max-age=86400", "X-Content-Type-Options": "nosniff"},
    )
