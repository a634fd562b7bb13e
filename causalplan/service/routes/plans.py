"""POST /v1/plans: plan a model on its object, or on another object through a step-3 mapping."""

from __future__ import annotations

from collections.abc import Callable

from fastapi import APIRouter, Request
from starlette.concurrency import run_in_threadpool

from causalplan.service import submissions
from causalplan.service.crud import ClientIds, PreparedModelRow
from causalplan.service.deps import ClientIdsDep, Services, ServicesDep
from causalplan.service.repeats import REPEAT_KEY
from causalplan.service.responses import SafeJSONResponse
from causalplan.service.schemas import PlanIn, PlanOut, error_responses

router = APIRouter(prefix="/v1/plans", tags=["plans"], responses=error_responses(404, 429, 503, 504))


@router.post("", response_model=PlanOut, summary="Plan a model")
async def create_plan(body: PlanIn, services: ServicesDep, client: ClientIdsDep, request: Request) -> SafeJSONResponse:
    """Plan how to assemble the object so the model's goal holds, and replay the plan on it.

    The same JSON as `causalplan plan --json`, plus `cached` (an identical request was
    answered before) and `model_id`. An inline model is stored, valid or not. An invalid
    model or mapping is answered with 422 and the CLI's codes.
    """
    # A body answered from the cache before is answered again by RepeatedPlanMiddleware, before
    # this route; a cached answer given here is kept under the key it left (see _response).
    repeat_key: str | None = request.scope.get(REPEAT_KEY)
    # A repeated request (documents read before, answer kept, record stored without waiting) is
    # answered here, on the event loop. Through HTTP, two servers interleaved, that took 0.34-0.44
    # ms less than the hop to a worker thread and back, about a fifth of such a request.
    # Everything that may wait (reading a new document, a free worker, a database server) goes
    # to a thread: one hop, the dependencies being `async def` (see deps). The worker's answer
    # is then waited for here, on the event loop, which it wakes directly (no thread to wake
    # and hop back from), and the response is made here too.
    kept = submissions.kept_answer(body, services, client, "plan")
    if kept is not None:
        return _response(body, services, *kept, repeat_key)
    sent: list[submissions.PendingAnswer] = []
    try:
        inputs, started = await run_in_threadpool(_start_plan, body, services, client, sent.append)
    except BaseException:  # cancelled while the thread ran: the answer it asked for will never be read
        for pending in sent:
            pending.abandon()
        raise
    answer = started if isinstance(started, submissions.Answer) else await started.reply()
    return _response(body, services, inputs, answer, repeat_key)


def _start_plan(
    body: PlanIn, services: Services, client: ClientIds, sent: Callable[[submissions.PendingAnswer], None]
) -> tuple[submissions.PlanInputs, submissions.Answer | submissions.PendingAnswer]:
    """Read the request and send it to a worker (or find its answer kept).

    ``sent`` is told of an answer sent for before it is returned (see ``create_plan``).
    """
    inputs = submissions.plan_inputs(body, services, client)
    # An inline model's record is stored while the worker solves (the two take ~0.16 ms and
    # ~8 ms), or at once for a kept answer; a request refused before a worker took it stores nothing.
    store = submissions.storing(services, inputs.submission)
    started = submissions.start_plan(
        services, inputs.model, inputs.mapping, inputs.planner, inputs.time_limit, inputs.key("plan"), store
    )
    if isinstance(started, submissions.PendingAnswer):
        sent(started)
    return inputs, started


def _response(
    body: PlanIn,
    services: Services,
    inputs: submissions.PlanInputs,
    answer: submissions.Answer,
    repeat_key: str | None,
) -> SafeJSONResponse:
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
    ).model_dump(mode="json")
    if repeat_key is not None and answer.cached and inputs.submission.is_new:  # an inline model's cached answer
        row = PreparedModelRow(services.engine, inputs.submission.record)
        services.repeats.keep(repeat_key, row, response, body.planner, inputs.planner)
    return SafeJSONResponse(response)
