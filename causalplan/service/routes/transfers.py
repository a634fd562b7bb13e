"""POST /v1/transfers: try a model on a new object (step 3) and store the trial."""

from __future__ import annotations

import uuid

from fastapi import APIRouter
from starlette.concurrency import run_in_threadpool

from causalplan.service import crud, submissions
from causalplan.service.cache import answer_key
from causalplan.service.crud import ClientIds
from causalplan.service.deps import ClientIdsDep, Services, ServicesDep
from causalplan.service.schemas import TransferIn, TransferOut, error_responses
from causalplan.transfer.verdict import invalid_verdict

router = APIRouter(prefix="/v1/transfers", tags=["transfers"], responses=error_responses(404, 429, 503, 504))


@router.post("", response_model=TransferOut, summary="Test whether a model transfers")
async def create_transfer(body: TransferIn, services: ServicesDep, client: ClientIdsDep) -> TransferOut:
    """Plan the model on the mapping's object and say whether it transfers, and why or why not.

    The same JSON as `causalplan transfer --json`, plus `cached`, `trial_id` and `model_id`.
    Every trial is stored with the inline model (if any) in one transaction. An invalid model
    or mapping is answered with 422 and the CLI's codes; that trial is stored too, as 'invalid'.
    """
    # A repeated trial is answered on the event loop, as a repeated plan is (see routes/plans.py).
    kept = submissions.kept_transfer(body, services, client)
    if kept is not None:
        answer, trial = kept
        return _response(body, answer, trial.id, trial.model_id)
    return await run_in_threadpool(_transfer, body, services, client)


def _transfer(body: TransferIn, services: Services, client: ClientIds) -> TransferOut:
    planner = submissions.resolve_planner(body.planner)
    time_limit = submissions.resolve_time_limit(body.time_limit, services.settings)
    submission = submissions.model_for_request(body.model, body.model_id, services, client)
    mapping_read, mapping_document = submissions.read_mapping(body.mapping, services)
    new_records = [submission.record] if submission.is_new else []
    problem = submissions.invalid_input_error(submission, mapping_read.report)
    if problem is not None:
        verdict = invalid_verdict(
            submission.report,
            mapping_read.report,
            submission.model.object_id if submission.model else None,
            str(mapping_document.get("object")) if mapping_document.get("object") is not None else None,
        ).as_dict()
        trial = crud.new_trial_record(submission.record.id, mapping_document, planner, verdict, False, 0.0, client)
        crud.save(services.engine, [*new_records, trial])
        problem.details.update({"verdict": verdict, "trial_id": str(trial.id)})
        raise problem
    mapping = mapping_read.mapping
    assert submission.model is not None and submission.canonical is not None
    assert mapping is not None and mapping_read.canonical is not None
    # The canonical texts are in hand: the key need not make them again.
    key = answer_key(
        "transfer", submission.canonical, mapping_read.canonical, planner, time_limit, services.catalog_key
    )
    answer = submissions.transfer(services, submission.model, mapping, planner, time_limit, key)
    trial = crud.new_trial_record(
        submission.record.id, mapping_document, planner, answer.data, answer.cached, answer.seconds, client
    )
    crud.save(services.engine, [*new_records, trial])
    return _response(body, answer, trial.id, submission.record.id)


def _response(body: TransferIn, answer: submissions.Answer, trial_id: uuid.UUID, model_id: uuid.UUID) -> TransferOut:
    return TransferOut.model_validate(
        {
            **answer.data,
            "planner_requested": body.planner,
            "cached": answer.cached,
            "trial_id": trial_id,
            "model_id": model_id,
        }
    )
