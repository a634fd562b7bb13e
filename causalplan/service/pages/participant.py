"""The participant's pages, at ``/p/<code>/...``: tutorial, step 1 per training object, step 2, step 3 per test object.

Every page works without JavaScript (a form posted and answered with the page again, with
any problems listed); the script adds saving as one types, live checking and the plan.
A page that is closed (finished, or not reached yet) sends the participant to where they are.
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Request, Response
from starlette.concurrency import run_in_threadpool

from causalplan.causal.diagnostics import Report
from causalplan.inputs import LoadedModel
from causalplan.objects.model import AssemblyObject
from causalplan.service.api.schemas.experiments import MAX_PART_TEXT, MAX_RULES_TEXT
from causalplan.service.deps import CatalogDep, ServicesDep, SessionDep, SettingsDep
from causalplan.service.errors import InvalidFormError
from causalplan.service.pages import revisions
from causalplan.service.pages.drawings import document_key
from causalplan.service.pages.ending import save_progress
from causalplan.service.pages.forms import Form, read_form
from causalplan.service.pages.journeys import JourneyDep, Number, here, page
from causalplan.service.pages.participation import picture_url, run_trial, submit_model
from causalplan.service.pages.revisions import form_revision
from causalplan.service.pages.templating import PageRoute, redirect
from causalplan.service.storage import arrivals
from causalplan.service.storage import experiments as store
from causalplan.service.storage.experiments import ParticipantJourney
from causalplan.studies.screening import comprehension_try
from causalplan.studies.steps import (
    Stage,
    check_functions,
    check_mapping,
    check_model,
    mapping_document,
    rule_lines,
    rules_from_text,
    unusable_label_notes,
)
from causalplan.studies.tutorial import (
    EXAMPLE_RULES,
    QUESTIONS,
    TUTORIAL_FUNCTIONS,
    TUTORIAL_OBJECT,
    practice_model,
    wrong_answers,
)

router = APIRouter(prefix="/p/{code}", route_class=PageRoute, include_in_schema=False)

Checked = Annotated[bool, Query(description="Sent back by a submission: show what it found to look at again.")]


def _parts(obj: AssemblyObject) -> list[dict[str, str]]:
    return [
        {"id": part.id, "name": part.name, "picture": f"/web/pictures/{obj.id}/{part.id}.png"} for part in obj.parts
    ]


def check_view(check: LoadedModel, rules_text: str) -> dict[str, Any]:
    """Return a model check as the pages show it: valid, and its errors and warnings with their lines."""
    _, lines = rules_from_text(rules_text)
    diagnostics = rule_lines(check.report, lines)
    return {
        "valid": check.is_valid,
        "errors": [item for item in diagnostics if item["severity"] == "error"],
        "warnings": [item for item in diagnostics if item["severity"] == "warning"],
    }


def graph_url(code: str, check: LoadedModel, document: dict[str, Any], practice: bool = False) -> str | None:
    """Return where the checked model's graph is (None when there is nothing to draw)."""
    if check.model is None:
        return None
    return f"/p/{code}/graph.svg?{'practice=1&' if practice else ''}v={document_key(document)}"


@router.get("", summary="Where the participant is")
def current(journey: JourneyDep) -> Response:
    return here(journey)


# -- tutorial ---------------------------------------------------------------------------------------------


def _tutorial_page(
    request: Request,
    journey: ParticipantJourney,
    catalog: CatalogDep,
    settings: SettingsDep,
    feedback: bool = False,
) -> Response:
    saved = journey.tutorial_work()
    rules_text = str(saved.get("rules", ""))
    answers: dict[str, str] = saved.get("answers", {})
    rules, _ = rules_from_text(rules_text)
    model = practice_model(tuple(rules), catalog)
    check = check_model(model, catalog, settings)
    car = catalog.get(TUTORIAL_OBJECT)
    return page(
        request,
        journey,
        "tutorial.html",
        answers_revision=journey.draft_revision(revisions.TUTORIAL_ANSWERS),
        rules_revision=journey.draft_revision(revisions.TUTORIAL_RULES),
        car=car,
        parts=_parts(car),
        functions=TUTORIAL_FUNCTIONS,
        example_rules=EXAMPLE_RULES,
        questions=QUESTIONS,
        answers=answers,
        wrong={question.id for question in wrong_answers(answers)} if feedback else set(),
        rules_text=rules_text,
        check=check_view(check, rules_text) if rules_text.strip() else None,
        graph_url=graph_url(journey.participant.code, check, model.merged_document(), practice=True) if rules else None,
        feedback=feedback,
        tries_left=_tries_left(journey),
    )


def _tries_left(journey: ParticipantJourney) -> int | None:
    """Return how many tries of the comprehension check are left (None: no limit, or passed)."""
    limit = journey.recruitment.comprehension_tries
    if limit is None or journey.has_passed_comprehension():
        return None
    return max(0, limit - len(journey.tutorial_work().get("tries", [])))


@router.get("/tutorial")
def tutorial(
    request: Request, journey: JourneyDep, catalog: CatalogDep, settings: SettingsDep, feedback: Checked = False
) -> Response:
    if not journey.may_open(Stage.TUTORIAL):
        return here(journey)
    return _tutorial_page(request, journey, catalog, settings, feedback=feedback)


@router.post("/tutorial")
async def finish_tutorial(
    request: Request, journey: JourneyDep, session: SessionDep, catalog: CatalogDep, settings: SettingsDep
) -> Response:
    journey.require_open(Stage.TUTORIAL)
    form = await read_form(request)
    answers = {question.id: form.text(f"answer:{question.id}", "", max_length=40) for question in QUESTIONS}
    rules_text = form.text("rules", "", max_length=MAX_RULES_TEXT)
    revision = form_revision(form)

    def submit() -> bool:
        """Store the answers, the rules (unless newer are stored) and the try; return True when screened out."""
        journey.require_open(Stage.TUTORIAL)
        if journey.accept_revision(revisions.TUTORIAL_ANSWERS, revision):
            journey.save_tutorial(answers=answers)
        revisions.save_rules(journey, rules_text, revision, practice=True)
        excluded = comprehension_try(journey, answers, not wrong_answers(answers))
        if excluded is not None:
            arrivals.exclude(session, journey.participant, excluded.reason, excluded.detail)
        return excluded is not None

    if store.change_participant(session, journey.participant, submit):
        return here(journey)
    rules, _ = rules_from_text(str(journey.tutorial_work().get("rules", "")))
    practice_ok = bool(rules) and check_model(practice_model(tuple(rules), catalog), catalog, settings).is_valid
    if wrong_answers(answers) or not practice_ok:
        # Post/redirect/get: a reload shows the page as saved, never sends this form again.
        return redirect(f"/p/{journey.participant.code}/tutorial?feedback=1")
    store.change_participant(session, journey.participant, journey.finish_tutorial)
    return here(journey)


# -- step 1 ---------------------------------------------------------------------------------------------


def _step1_page(
    request: Request,
    journey: ParticipantJourney,
    index: int,
    report: Report | None = None,
    noted: str = "",
) -> Response:
    obj = journey.training[index]
    return page(
        request,
        journey,
        "step1.html",
        revision=journey.draft_revision(revisions.functions_key(obj.id)),
        index=index,
        obj=obj,
        parts=_parts(obj),
        texts=journey.function_texts(obj.id),
        used_labels=journey.draft_model().function_labels(),
        problems=[d.as_dict() for d in report.diagnostics] if report is not None else [],
        may_go_back=index > 0,
        noted=noted,
    )


@router.get("/step1/{number}")
def step1(
    request: Request,
    journey: JourneyDep,
    number: Number,
    catalog: CatalogDep,
    settings: SettingsDep,
    check: Checked = False,
) -> Response:
    if not journey.may_open(Stage.STEP1, number - 1):
        return here(journey)
    if not check:
        return _step1_page(request, journey, number - 1)
    # Sent here by a submission that needs another look: its problems, or its notes to confirm.
    obj = journey.training[number - 1]
    report = check_functions(obj, journey.function_texts(obj.id), catalog, settings)
    notes = unusable_label_notes(report) if report.is_valid else ""
    return _step1_page(request, journey, number - 1, report, noted=notes)


@router.post("/step1/{number}")
async def finish_step1(
    request: Request,
    journey: JourneyDep,
    number: Number,
    session: SessionDep,
    catalog: CatalogDep,
    settings: SettingsDep,
) -> Response:
    index = number - 1
    journey.require_open(Stage.STEP1, index)
    obj = journey.training[index]
    form = await read_form(request)
    texts = {part: form.text(f"part:{part}", "", max_length=MAX_PART_TEXT) for part in obj.part_ids}
    revision = form_revision(form)

    def save() -> None:
        journey.require_open(Stage.STEP1, index)
        if journey.accept_revision(revisions.functions_key(obj.id), revision):
            journey.save_functions(obj.id, texts)

    store.change_participant(session, journey.participant, save)
    report = check_functions(obj, journey.function_texts(obj.id), catalog, settings)
    notes = unusable_label_notes(report)
    # shown once; sent again as it is, it goes on
    if not report.is_valid or (notes and form.text("noted", "", max_length=64) != notes):
        # Post/redirect/get: a reload shows the page as saved, never sends this form again.
        return redirect(f"/p/{journey.participant.code}/step1/{number}?check=1")
    store.change_participant(session, journey.participant, lambda: journey.finish_functions(index))
    code = journey.participant.code
    return redirect(f"/p/{code}/step1/{number + 1}" if number < len(journey.training) else f"/p/{code}/step2")


# -- step 2 ---------------------------------------------------------------------------------------------


def _step2_page(
    request: Request, journey: ParticipantJourney, catalog: CatalogDep, settings: SettingsDep, submitted: bool = False
) -> Response:
    model = journey.draft_model()
    rules_text = journey.rules_text()
    check = check_model(model, catalog, settings)
    return page(
        request,
        journey,
        "step2.html",
        submitted=submitted,
        revision=journey.draft_revision(revisions.STEP2_RULES),
        functions=[
            (obj, [(part, model.functions[obj.id].get(part.id, [])) for part in obj.parts]) for obj in journey.training
        ],
        labels=model.function_labels(),
        rules_text=rules_text,
        check=check_view(check, rules_text),
        graph_url=graph_url(journey.participant.code, check, model.merged_document()),
    )


@router.get("/step2")
def step2(
    request: Request, journey: JourneyDep, catalog: CatalogDep, settings: SettingsDep, check: Checked = False
) -> Response:
    if not journey.may_open(Stage.STEP2):
        return here(journey)
    return _step2_page(request, journey, catalog, settings, submitted=check)


@router.post("/step2")
async def finish_step2(
    request: Request, journey: JourneyDep, session: SessionDep, catalog: CatalogDep, settings: SettingsDep
) -> Response:
    journey.require_open(Stage.STEP2)
    form = await read_form(request)
    text = form.text("rules", "", max_length=MAX_RULES_TEXT)
    revision = form_revision(form)
    store.change_participant(session, journey.participant, lambda: revisions.save_rules(journey, text, revision))
    model = journey.draft_model()
    check = check_model(model, catalog, settings)
    if not check.is_valid:
        # Submission is blocked while the model is invalid. Post/redirect/get: the page comes back
        # with the problems, and a reload shows the rules as saved, never sends this form again.
        return redirect(f"/p/{journey.participant.code}/step2?check=1")
    submit_model(session, journey, model, check)
    return here(journey)


# -- step 3 ---------------------------------------------------------------------------------------------


def _step3_page(
    request: Request,
    journey: ParticipantJourney,
    index: int,
    session: SessionDep,
    report: Report | None = None,
) -> Response:
    obj = journey.tests[index]
    model = journey.submitted_model()
    assert model is not None, "step 3 begins when the model is submitted"
    stored = store.trial_of(session, journey.participant, obj.id)
    code = journey.participant.code
    result = stored.trial.result if stored is not None else None
    return page(
        request,
        journey,
        "step3.html",
        revision=journey.draft_revision(revisions.mapping_key(obj.id)),
        index=index,
        obj=obj,
        parts=_parts(obj),
        model=model,
        labels=model.function_labels(),
        entries=journey.mapping_entries(obj.id),
        graph_url=f"/p/{code}/graph.svg?v={document_key(model.merged_document())}",
        problems=[d.as_dict() for d in report.diagnostics] if report is not None else [],
        result=result,
        show_verdict=journey.design.show_verdict,
        picture_url=picture_url(code, obj.id, result.get("plan") if result else None),
        is_last=index + 1 == len(journey.tests),
    )


@router.get("/step3/{number}")
def step3(
    request: Request,
    journey: JourneyDep,
    number: Number,
    session: SessionDep,
    catalog: CatalogDep,
    settings: SettingsDep,
    check: Checked = False,
) -> Response:
    if not journey.may_open(Stage.STEP3, number - 1):
        return here(journey)
    report = None
    if check and store.trial_of(session, journey.participant, journey.tests[number - 1].id) is None:
        obj = journey.tests[number - 1]
        report = check_mapping(mapping_document(obj, journey.mapping_entries(obj.id)), catalog, settings).report
    return _step3_page(request, journey, number - 1, session, report)


def mapping_entries_from_form(form_fields: Form, obj: AssemblyObject, labels: list[str]) -> dict[str, dict[str, Any]]:
    """Return step 3's entries from the form: per part, the model's functions ticked and new lines."""
    entries: dict[str, dict[str, Any]] = {}
    for part in obj.part_ids:
        chosen = form_fields.texts(f"chosen:{part}", max_count=len(labels) + 1, max_length=200)
        unknown = [label for label in chosen if label not in labels]
        if unknown:
            raise InvalidFormError(
                f"'{unknown[0]}' is not a function of your model; write new functions in the box instead.",
                details={"part": part},
            )
        entries[part] = {"chosen": chosen, "added": form_fields.text(f"added:{part}", "", max_length=MAX_PART_TEXT)}
    return entries


@router.post("/step3/{number}")
async def submit_step3(
    request: Request,
    journey: JourneyDep,
    number: Number,
    services: ServicesDep,
    session: SessionDep,
    catalog: CatalogDep,
    settings: SettingsDep,
) -> Response:
    index = number - 1
    journey.require_open(Stage.STEP3, index)
    obj = journey.tests[index]
    model = journey.submitted_model()
    assert model is not None, "step 3 begins when the model is submitted"
    if store.trial_of(session, journey.participant, obj.id) is not None:
        return here(journey)  # a second click of Submit: the answer is in
    form = await read_form(request)
    entries = mapping_entries_from_form(form, obj, model.function_labels())
    revision = form_revision(form)

    def save() -> None:
        journey.require_open(Stage.STEP3, index)
        if journey.accept_revision(revisions.mapping_key(obj.id), revision):
            journey.save_mapping(obj.id, entries)

    store.change_participant(session, journey.participant, save)
    checked = check_mapping(mapping_document(obj, journey.mapping_entries(obj.id)), catalog, settings)
    if not checked.is_valid:
        # Post/redirect/get: a reload shows the choices as saved, never sends this form again.
        return redirect(f"/p/{journey.participant.code}/step3/{number}?check=1")
    # The trial waits on a planner worker for up to the time limit: off the event loop, so other
    # participants' pages are served meanwhile.
    await run_in_threadpool(run_trial, services, session, journey, index, checked)
    return redirect(f"/p/{journey.participant.code}/step3/{number}")


@router.post("/step3/{number}/next")
def next_test(journey: JourneyDep, number: Number, session: SessionDep) -> Response:
    index = number - 1
    journey.require_open(Stage.STEP3, index)
    if store.trial_of(session, journey.participant, journey.tests[index].id) is None:
        return here(journey)  # nothing submitted yet for this object
    journey.finish_test(index)
    save_progress(session, journey)
    return here(journey)
