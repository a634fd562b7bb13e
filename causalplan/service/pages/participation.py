"""What a participant's actions do: plan their draft model, submit it, and run a step-3 trial.

Models and trials go into the service's own tables (``models``, ``trials``), exactly as the
JSON API stores them, so ``GET /v1/trials`` and ``/v1/export`` have them too; the
experiment's ``participant_trials`` row links each trial to its participant.
"""

from __future__ import annotations

from typing import Any

from sqlalchemy.orm import Session

from causalplan.causal.canonical import model_hash
from causalplan.explain.questions import example_questions
from causalplan.inputs import LoadedModel
from causalplan.planners.result import PlanStep
from causalplan.service.deps import Services
from causalplan.service.documents import default_planner, first_errors
from causalplan.service.errors import InvalidModelError
from causalplan.service.storage import crud
from causalplan.service.storage.crud import PAGE_SESSION_PREFIX, ClientIds
from causalplan.service.storage.experiments import ParticipantJourney
from causalplan.service.storage.participation import store_submitted_model, store_trial
from causalplan.service.work.planning import PlanArguments, TransferArguments
from causalplan.service.work.registry import PLAN, TRANSFER
from causalplan.studies.errors import StepLockedError
from causalplan.studies.steps import MappingCheck, ParticipantModel, Stage, model_on


def client_ids(journey: ParticipantJourney) -> ClientIds:
    """Return who the stored records are from: the participant's id and the experiment's."""
    return ClientIds(str(journey.participant.id), f"{PAGE_SESSION_PREFIX}{journey.participant.experiment_id}")


def invalid_model_error(check: LoadedModel) -> InvalidModelError:
    """Return the 422 error of an invalid draft model (details: the report, with `check`'s codes)."""
    return InvalidModelError(
        "The model is not valid yet: " + first_errors(check.report),
        details={"model": check.report.as_dict()},
    )


def picture_url(code: str, object_id: str, steps: list[dict[str, Any]] | None) -> str | None:
    """Return where the simulator's picture of the object after a plan's ``steps`` is (None without a plan)."""
    fits = [str(step.get("fit") or "") for step in steps or []]
    return f"/p/{code}/pictures/{object_id}.png?fits={','.join(fits)}" if fits and all(fits) else None


def plans(services: Services, journey: ParticipantJourney, participant_model: ParticipantModel) -> list[dict[str, Any]]:
    """Return the robot's plan of the (valid) model on each training object, with where its picture is."""
    planner = default_planner()
    found = []
    for obj in journey.training:
        arguments = PlanArguments(
            model_on(participant_model, obj.id), None, planner, services.settings.default_time_limit
        )
        answer = services.work.answer(PLAN, arguments)
        steps = answer.data.get("plan") or []
        attached = [PlanStep(str(s["action"]), tuple(s["args"]), str(s["fit"]), str(s["text"])) for s in steps]
        found.append(
            {
                "object": obj.id,
                "name": obj.name,
                "status": str(answer.data["status"]),
                "steps": [str(step["text"]) for step in steps],
                "message": str(answer.data.get("message", "")),
                "works": bool(answer.data.get("valid_under_true_mechanism")),
                "picture_url": picture_url(journey.participant.code, obj.id, steps),
                "fits": [str(step.get("fit") or "") for step in steps],
                "questions": example_questions(obj, attached) if steps else [],
            }
        )
    return found


def submit_model(
    session: Session, journey: ParticipantJourney, participant_model: ParticipantModel, check: LoadedModel
) -> None:
    """Store the valid model (as the first training object's model file), freeze it, and begin step 3."""
    journey.require_open(Stage.STEP2)
    if not check.is_valid or check.model is None:
        raise invalid_model_error(check)
    first = journey.training[0].id
    record = crud.new_model_record(
        participant_model.document(first),
        first,
        True,
        check.report.as_dict(),
        model_hash(model_on(participant_model, first)),
        client_ids(journey),
    )
    store_submitted_model(session, journey, participant_model, record)


def run_trial(
    services: Services, session: Session, journey: ParticipantJourney, index: int, mapping: MappingCheck
) -> None:
    """Try the participant's model on test object ``index`` through their mapping; store the trial.

    The caller has checked that the participant has no trial on this object yet (a second one
    would break the link table's unique constraint).
    """
    journey.require_open(Stage.STEP3, index)
    participant_model = journey.submitted_model()
    model_id = journey.participant.model_id
    if participant_model is None or model_id is None or mapping.mapping is None:
        raise StepLockedError("There is no submitted model or valid mapping to try.")
    test = journey.tests[index]
    planner = default_planner()
    model = model_on(participant_model, journey.training[0].id)
    limit = services.settings.default_time_limit
    arguments = TransferArguments(model, mapping.mapping, planner, limit, robot=journey.design.robot_verdict)
    answer = services.work.answer(TRANSFER, arguments)
    trial = crud.new_trial_record(
        model_id, mapping.document, planner, answer.data, answer.cached, answer.seconds, client_ids(journey)
    )
    store_trial(session, journey, trial, test.id, index)
