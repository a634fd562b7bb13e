"""The small JSON endpoints of the participant pages, at ``/p/<code>/...``: save, check, plan, pictures.

Errors come in the service's one JSON shape; a step that is closed answers 409 ``step_locked``.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, Response

from causalplan.service.api.schemas.common import OutputModel, UtcDatetime
from causalplan.service.api.schemas.experiments import (
    CheckIn,
    CheckOut,
    DraftIn,
    FunctionsDraftIn,
    MappingDraftIn,
    PlanIn,
    PlansOut,
    SavedOut,
    TutorialDraftIn,
)
from causalplan.service.deps import CatalogDep, ServicesDep, SessionDep, SettingsDep
from causalplan.service.errors import InvalidRequestError, NotFoundError
from causalplan.service.pages import revisions
from causalplan.service.pages.drawings import document_key, fresh_svg, graph_svg, plan_picture
from causalplan.service.pages.journeys import JourneyDep
from causalplan.service.pages.participant import check_view, graph_url
from causalplan.service.pages.participation import invalid_model_error, plans
from causalplan.service.pages.robot_films import run_ahead
from causalplan.service.storage import experiments as store
from causalplan.service.storage.experiments import ParticipantJourney
from causalplan.service.storage.records import utc_now
from causalplan.studies.errors import StepLockedError
from causalplan.studies.steps import ParticipantModel, Stage, check_model, rules_from_text
from causalplan.studies.tutorial import QUESTIONS, practice_model

router = APIRouter(prefix="/p/{code}", include_in_schema=False)

PRIVATE = {"Cache-Control": "private, max-age=3600", "X-Content-Type-Options": "nosniff"}


def _unknown_parts(parts: list[str], allowed: tuple[str, ...], object_name: str) -> None:
    unknown = [part for part in parts if part not in allowed]
    if unknown:
        raise InvalidRequestError(
            f"The {object_name} has no part '{unknown[0]}'.", details={"part": unknown[0], "parts": list(allowed)}
        )


def _save_draft(
    journey: ParticipantJourney, draft: TutorialDraftIn | FunctionsDraftIn | MappingDraftIn, session: SessionDep
) -> bool:
    """Save a draft unless a newer one of its boxes is stored; return whether it was saved."""
    if isinstance(draft, TutorialDraftIn):
        journey.require_open(Stage.TUTORIAL)
        if not journey.accept_revision(revisions.TUTORIAL_ANSWERS, draft.revision):
            return False
        known = {question.id for question in QUESTIONS}
        journey.save_tutorial(answers={key: value for key, value in draft.answers.items() if key in known})
        return True
    if isinstance(draft, FunctionsDraftIn):
        index = next((i for i, obj in enumerate(journey.training) if obj.id == draft.object), -1)
        journey.require_open(Stage.STEP1, index)
        obj = journey.training[index]
        _unknown_parts(list(draft.functions), obj.part_ids, obj.name)
        if not journey.accept_revision(revisions.functions_key(obj.id), draft.revision):
            return False
        journey.save_functions(obj.id, dict(draft.functions))
        return True
    index = next((i for i, obj in enumerate(journey.tests) if obj.id == draft.object), -1)
    journey.require_open(Stage.STEP3, index)
    obj = journey.tests[index]
    if store.trial_of(session, journey.participant, obj.id) is not None:
        raise StepLockedError(f"Your answer for the {obj.name} is already recorded; it cannot change.")
    _unknown_parts(list(draft.mapping), obj.part_ids, obj.name)
    if not journey.accept_revision(revisions.mapping_key(obj.id), draft.revision):
        return False
    journey.save_mapping(obj.id, {part: entry.model_dump() for part, entry in draft.mapping.items()})
    return True


def _draft_key(draft: TutorialDraftIn | FunctionsDraftIn | MappingDraftIn) -> str:
    if isinstance(draft, TutorialDraftIn):
        return revisions.TUTORIAL_ANSWERS
    if isinstance(draft, FunctionsDraftIn):
        return revisions.functions_key(draft.object)
    return revisions.mapping_key(draft.object)


@router.post("/draft", response_model=SavedOut)
def save_draft(draft: DraftIn, journey: JourneyDep, session: SessionDep) -> SavedOut:
    """Save what the participant has typed so far on the step they are on (unless newer text is stored)."""
    applied = store.change_participant(session, journey.participant, lambda: _save_draft(journey, draft, session))
    saved_at = journey.participant.updated_at or utc_now()
    return SavedOut(saved=True, saved_at=saved_at, revision=journey.draft_revision(_draft_key(draft)), applied=applied)


@router.post("/check", response_model=CheckOut)
def check_rules(
    body: CheckIn, journey: JourneyDep, session: SessionDep, catalog: CatalogDep, settings: SettingsDep
) -> CheckOut:
    """Save the rule box and check the rules as typed, as `causalplan check` does; say where its graph is."""
    applied = store.change_participant(
        session, journey.participant, lambda: revisions.save_rules(journey, body.rules, body.revision, body.practice)
    )
    model: ParticipantModel
    if body.practice:
        rules, _ = rules_from_text(body.rules)
        model = practice_model(tuple(rules), catalog)
    else:
        model = journey.draft_model(body.rules)
    check = check_model(model, catalog, settings)
    key = revisions.TUTORIAL_RULES if body.practice else revisions.STEP2_RULES
    return CheckOut.model_validate(
        {
            **check_view(check, body.rules),
            "graph_url": graph_url(journey.participant.code, check, model.merged_document(), body.practice),
            "saved_at": journey.participant.updated_at or utc_now(),
            "revision": journey.draft_revision(key),
            "applied": applied,
        }
    )


@router.post("/plan", response_model=PlansOut)
def show_plan(
    body: PlanIn,
    journey: JourneyDep,
    services: ServicesDep,
    session: SessionDep,
    catalog: CatalogDep,
    settings: SettingsDep,
) -> PlansOut:
    """Save the rule box, then plan the rules as typed on each training object: the steps in words, and the picture."""
    journey.require_open(Stage.STEP2)
    store.change_participant(
        session, journey.participant, lambda: revisions.save_rules(journey, body.rules, body.revision)
    )
    model = journey.draft_model(body.rules)
    check = check_model(model, catalog, settings)
    if not check.is_valid:
        raise invalid_model_error(check)
    found = plans(services, journey, model)
    objects = {obj.id: obj for obj in journey.training}
    run_ahead(services, [(objects[plan["object"]], plan["fits"]) for plan in found])  # "Watch the robot" is next
    # Planning takes a while: the log goes onto the record as stored now, which a check may have changed.
    store.change_participant(session, journey.participant, lambda: journey.log_plan_request(utc_now(), model.rules))
    return PlansOut.model_validate({"plans": found})


class ProgressOut(OutputModel):
    """Where the participant is, as stored: the end page leaves for the platform only once ``finished``."""

    stage: str
    finished: bool
    saved_at: UtcDatetime | None


@router.get("/progress", response_model=ProgressOut)
def progress(journey: JourneyDep) -> ProgressOut:
    """Say where the participant is as the database has it now (never cached)."""
    finished = journey.stage in (Stage.DONE, Stage.SCREENED) and journey.participant.finished_at is not None
    return ProgressOut(stage=journey.stage.value, finished=finished, saved_at=journey.participant.updated_at)


NOTHING_TO_DRAW = (
    b'<svg xmlns="http://www.w3.org/2000/svg" width="320" height="60" role="img">'
    b'<text x="10" y="35" font-family="sans-serif" font-size="14" fill="#555">'
    b"Nothing to draw yet: write a rule.</text></svg>"
)


@router.get("/graph.svg")
def graph(
    journey: JourneyDep,
    services: ServicesDep,
    catalog: CatalogDep,
    settings: SettingsDep,
    practice: Annotated[bool, Query()] = False,
    v: Annotated[str, Query(max_length=64)] = "",
) -> Response:
    """Draw the participant's model: the tutorial's practice, the draft, or (from step 3) the submitted one."""
    del v  # only there so each version of the model has its own URL
    model: ParticipantModel | None
    if practice:
        rules, _ = rules_from_text(str(journey.tutorial_work().get("rules", "")))
        model = practice_model(tuple(rules), catalog)
    elif journey.participant.model_id is not None:  # step 2 is submitted: the model is fixed
        model = journey.submitted_model()
    else:
        model = journey.draft_model()
    svg = None
    if model is not None:
        key = document_key(model.merged_document())
        svg = graph_svg(services, key, lambda: check_model(model, catalog, settings).model)
    return fresh_svg(svg or NOTHING_TO_DRAW)


@router.get("/pictures/{object_id}.png")
def picture(
    object_id: str,
    journey: JourneyDep,
    services: ServicesDep,
    fits: Annotated[str, Query(max_length=2000, description="The plan's fits, in order, separated by commas.")],
) -> Response:
    """Return the simulator's picture of one of the participant's objects after a plan."""
    obj = next((o for o in (*journey.training, *journey.tests) if o.id == object_id), None)
    if obj is None:
        raise NotFoundError(f"'{object_id}' is not one of your objects.")
    fit_ids = tuple(fit for fit in fits.split(",") if fit)
    known = {fit.id for fit in obj.fits}
    if not fit_ids or any(fit not in known for fit in fit_ids):
        raise InvalidRequestError(f"'fits' must name fits of the {obj.name}: {', '.join(sorted(known))}.")
    return Response(plan_picture(services, obj, fit_ids), media_type="image/png", headers=PRIVATE)
