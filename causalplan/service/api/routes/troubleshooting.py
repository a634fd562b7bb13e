"""POST /v1/troubleshooting: repair a broken object with a person's causal model, beside the baselines."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from causalplan.service.api.schemas.common import error_responses
from causalplan.service.api.schemas.troubleshooting import TroubleshootingIn, TroubleshootingOut
from causalplan.service.deps import ClientIdsDep, ServicesDep
from causalplan.service.documents import StrictJSONRoute, invalid_input_error, model_for_request, read_mapping
from causalplan.service.storage.crud import save
from causalplan.troubleshoot.answer import episode_answer, table_answer
from causalplan.troubleshoot.task import troubleshooting_task

MAX_SERVICE_STATES = 500_000
"""The (belief, assembly) states one request may solve, about a second of work: the catalog's objects need
at most a few thousand. The solve runs on the request's thread; beyond this it is refused (422)."""

router = APIRouter(
    prefix="/v1/troubleshooting",
    tags=["troubleshooting"],
    responses=error_responses(403, 404, 429),
    route_class=StrictJSONRoute,
)


@router.post("", response_model=TroubleshootingOut, summary="Troubleshoot a broken object")
def create_troubleshooting(body: TroubleshootingIn, services: ServicesDep, client: ClientIdsDep) -> dict[str, Any]:
    """Solve the model's, uniform's and the oracle's exact policies on the broken object, and score them.

    Solved on the request's thread (a catalog object takes milliseconds), within a bound on the
    solver's states (``troubleshooting_too_large`` beyond it).

    The same JSON as `causalplan troubleshoot --all-faults --json`, with `episode` (as
    `--fault PART --json`) when `fault` is given, and `model_id`. An inline model is stored,
    valid or not. Bad input is 422 with a code: `unknown_fault_part`, `fault_not_needed`,
    `object_without_faults`, `mapping_does_not_fit`, `troubleshooting_too_large`, or the
    model's and mapping's validation codes; an unknown object is 404.
    """
    submission = model_for_request(body.model, body.model_id, services, client)
    mapping = read_mapping(body.mapping, services) if body.mapping is not None else None
    if submission.is_new:
        save(services.engine, [submission.record])
    problem = invalid_input_error(submission, mapping.report if mapping is not None else None)
    if problem is not None:
        raise problem
    assert submission.model is not None
    labelling = mapping.mapping if mapping is not None else None
    chosen = body.object or (labelling or submission.model.labelling).object_id
    task = troubleshooting_task(services.catalog.get(chosen), submission.model, labelling, MAX_SERVICE_STATES)
    episode = episode_answer(task, body.fault, body.strategy) if body.fault is not None else None
    warnings = [*submission.report.warnings, *(mapping.report.warnings if mapping is not None else [])]
    return {
        **table_answer(task),
        "episode": episode,
        "model_id": submission.record.id,
        "warnings": [warning.as_dict() for warning in warnings],
    }
