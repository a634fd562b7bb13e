"""POST /v1/transfers: try a model on a new object (step 3) and store the trial."""

from __future__ import annotations

from fastapi import APIRouter

from causalplan.service.api.schemas.common import error_responses
from causalplan.service.api.schemas.plans import TransferIn, TransferOut
from causalplan.service.deps import ClientIdsDep, ServicesDep
from causalplan.service.documents import (
    StrictJSONRoute,
    invalid_input_error,
    model_for_request,
    read_mapping,
    resolve_planner,
    resolve_time_limit,
)
from causalplan.service.storage import crud
from causalplan.service.work.planning import RepairArguments, TransferArguments
from causalplan.service.work.registry import REPAIRS, TRANSFER
from causalplan.transfer.verdict import invalid_verdict

router = APIRouter(
    prefix="/v1/transfers",
    tags=["transfers"],
    responses=error_responses(403, 404, 429, 503, 504),
    route_class=StrictJSONRoute,
)


@router.post(
    "", response_model=TransferOut, response_model_exclude_unset=True, summary="Test whether a model transfers"
)
def create_transfer(body: TransferIn, services: ServicesDep, client: ClientIdsDep) -> TransferOut:
    """Plan the model on the mapping's object and say whether it transfers, and why or why not.

    The same JSON as `causalplan transfer --json`, plus `cached`, `trial_id` and `model_id`.
    Every trial is stored with the inline model (if any) in one transaction. An invalid model
    or mapping is answered with 422 and the CLI's codes; that trial is stored too, as 'invalid'.
    """
    planner = resolve_planner(body.planner)
    time_limit = resolve_time_limit(body.time_limit, services.settings)
    submission = model_for_request(body.model, body.model_id, services, client)
    mapping = read_mapping(body.mapping, services)
    new_records = [submission.record] if submission.is_new else []
    problem = invalid_input_error(submission, mapping.report)
    if problem is not None:
        test_object = mapping.document.get("object")
        verdict = invalid_verdict(
            submission.report,
            mapping.report,
            submission.model.object_id if submission.model else None,
            str(test_object) if test_object is not None else None,
        ).as_dict()
        trial = crud.new_trial_record(submission.record.id, mapping.document, planner, verdict, False, 0.0, client)
        crud.save(services.engine, [*new_records, trial], client)
        problem.details.update({"verdict": verdict, "trial_id": str(trial.id)})
        raise problem
    assert submission.model is not None and mapping.mapping is not None
    model, val = submission.model, body.validate_plan
    answer = services.work.answer(TRANSFER, TransferArguments(model, mapping.mapping, planner, time_limit, val))
    trial = crud.new_trial_record(
        submission.record.id, mapping.document, planner, answer.data, answer.cached, answer.seconds, client
    )
    crud.save(services.engine, [*new_records, trial], client)
    repairs = None
    if body.repair and answer.data["verdict"] == "fails":
        budget = services.settings.search_seconds  # its own, whatever time_limit is: it stops with what it found
        repairs = services.work.run(REPAIRS, RepairArguments(model, mapping.mapping, planner, time_limit, val, budget))
    return TransferOut.model_validate(
        {
            **answer.data,
            "repairs": repairs,
            "planner_requested": body.planner,
            "cached": answer.cached,
            "trial_id": trial.id,
            "model_id": submission.record.id,
        }
    )
