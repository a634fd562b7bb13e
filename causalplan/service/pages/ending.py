"""The pages that end the study, at ``/p/<code>/...``: the demographic questions, the end, and screened out.

A participant from a crowd platform is handed back to it: to Prolific's completion URL with the
experiment's code for how they ended, or by a form posted to MTurk's ``externalSubmit``.
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request, Response

from causalplan.service.deps import SessionDep
from causalplan.service.errors import InvalidFormError
from causalplan.service.pages.forms import read_form
from causalplan.service.pages.journeys import JourneyDep, common, framing, here, page
from causalplan.service.pages.templating import PageRoute, render
from causalplan.service.storage import arrivals
from causalplan.service.storage import experiments as store
from causalplan.service.storage.experiments import ParticipantJourney
from causalplan.studies import recruitment
from causalplan.studies.screening import too_fast
from causalplan.studies.steps import Stage

router = APIRouter(prefix="/p/{code}", route_class=PageRoute, include_in_schema=False)


def save_progress(session: SessionDep, journey: ParticipantJourney) -> None:
    """Store the participant's move; one who has just finished too fast is flagged, with the reason."""
    flagged = too_fast(journey)
    excluded = [arrivals.exclusion(journey.participant, flagged.reason, flagged.detail)] if flagged else []
    store.save(session, journey.participant, *excluded)


@router.get("/about")
def about(request: Request, journey: JourneyDep) -> Response:
    if not journey.may_open(Stage.ABOUT):
        return here(journey)
    return page(request, journey, "about.html", questions=journey.recruitment.questions())


@router.post("/about")
async def finish_about(request: Request, journey: JourneyDep, session: SessionDep) -> Response:
    journey.require_open(Stage.ABOUT)
    form = await read_form(request)
    answers = {}
    for question in journey.recruitment.questions():
        answer = form.text(question.id, "", max_length=40).strip()
        if question.choices and answer and answer not in question.choices:
            raise InvalidFormError(f"'{question.text}' has no such answer.", details={"field": question.id})
        if not question.choices and answer and not (answer.isdigit() and question.low <= int(answer) <= question.high):
            raise InvalidFormError(
                f"'{question.text}': write a whole number from {question.low} to {question.high}, or leave it empty.",
                details={"field": question.id},
            )
        answers[question.id] = answer
    journey.finish_demographics(answers)
    save_progress(session, journey)
    return here(journey)


def finish_page(request: Request, journey: ParticipantJourney, template: str, outcome: str, **context: Any) -> Response:
    """Return a page that ends the study, with the way back to the participant's platform."""
    arrival = journey.participant.arrival
    codes = {"completed": journey.recruitment.completion_code, "screened_out": journey.recruitment.screened_out_code}
    back = (
        recruitment.finish(arrival.platform, arrival.platform_session, arrival.submit_to, codes[outcome], outcome)
        if arrival is not None
        else None
    )
    return render(
        request,
        template,
        secret_url=True,
        framed_by=framing(journey),
        posts_to=(back.origin,) if back is not None and back.fields else (),
        **common(journey),
        back=back,
        redirect_seconds=recruitment.REDIRECT_SECONDS,
        **context,
    )


@router.get("/done")
def done(request: Request, journey: JourneyDep, session: SessionDep) -> Response:
    if not journey.may_open(Stage.DONE):
        return here(journey)
    stored = store.trials_by_test(session, journey.participant)
    return finish_page(
        request,
        journey,
        "done.html",
        "completed",
        results=[(obj, stored[obj.id].trial.verdict if obj.id in stored else None) for obj in journey.tests],
        show_verdict=journey.design.show_verdict,
    )


@router.get("/screened")
def screened(request: Request, journey: JourneyDep) -> Response:
    if not journey.may_open(Stage.SCREENED):
        return here(journey)
    return finish_page(request, journey, "screened.html", "screened_out")
