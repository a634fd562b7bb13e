"""The public study link, ``/s/<experiment>``: arrival from a crowd platform (or none), consent, and admission.

The link is what a researcher puts on Prolific or in an MTurk external question. Arriving
stores only the arrival (with the platform's ids); consenting admits the person to the open
condition with the fewest participants and sends them to their own participant pages;
declining ends politely, with the platform's no-consent code. The same platform session (the
platform id with Prolific's SESSION_ID or MTurk's assignmentId) coming back finds its own
arrival: consent again if undecided, their progress if admitted. The platform id alone finds
nothing, so a bot that copies someone's PROLIFIC_PID cannot decide for them or take their record.

In the open: a client may make ``arrivals_per_minute`` new arrivals a minute; a study may
refuse arrivals without platform ids; an admitted person holds a place only while at work
(``studies.assignment.PlaceRules``), so a bot that agrees and leaves cannot keep a study full;
and one client address may hold ``places_per_client`` places admitted but not started (more
consents from it get "please try again later"), so a bot looping from one address cannot either.
"""

from __future__ import annotations

import uuid
from typing import Any

from fastapi import APIRouter, Request, Response

from causalplan.service.deps import ServicesDep, SessionDep, client_address
from causalplan.service.errors import ClientHoldsPlacesError, InvalidFormError, TooManyArrivalsError
from causalplan.service.experiments import place_rules
from causalplan.service.pages.forms import read_form
from causalplan.service.pages.templating import PageRoute, redirect, render
from causalplan.service.storage import arrivals
from causalplan.service.storage import experiments as store
from causalplan.service.storage.records import ExperimentRecord
from causalplan.service.storage.throttle import PerMinute
from causalplan.studies import recruitment
from causalplan.studies.errors import PlatformIdRequiredError
from causalplan.studies.recruitment import MTURK_FRAME_ORIGINS, PlatformVisit, Recruitment, finish, read_visit

router = APIRouter(prefix="/s/{experiment_id}", route_class=PageRoute, include_in_schema=False)


def _page(request: Request, template: str, platform: str, status_code: int = 200, **context: Any) -> Response:
    framed_by = MTURK_FRAME_ORIGINS if platform == "mturk" else ()
    return render(request, template, status_code=status_code, secret_url=True, framed_by=framed_by, **context)


def _full(request: Request, platform: str) -> Response:
    return _page(
        request, "study_message.html", platform, kind="full", back=None, redirect_seconds=recruitment.REDIRECT_SECONDS
    )


def _require_platform(recruiting: Recruitment, platform: str) -> None:
    if recruiting.require_platform_id and platform == "direct":
        raise PlatformIdRequiredError(
            "This study is open only to participants of a crowd platform: "
            "please open it from its page on Prolific or Amazon Mechanical Turk."
        )


@router.get("")
def arrive(request: Request, experiment_id: uuid.UUID, session: SessionDep, services: ServicesDep) -> Response:
    experiment = store.get_experiment(session, experiment_id)
    visit = read_visit(dict(request.query_params))
    recruiting = Recruitment.from_dict(experiment.recruitment)
    if visit.is_preview:  # MTurk's preview: show what the study is, store nothing
        return _consent_page(request, experiment, visit, recruiting, None)
    _require_platform(recruiting, visit.platform)
    found = arrivals.find_arrival(session, experiment.id, visit)
    if found is not None and found.participant is not None:
        return redirect(f"/p/{found.participant.code}")  # they come back to their own progress
    if found is not None and found.consented is False:
        return _declined(request, found, recruiting)
    if found is None and arrivals.is_full(session, experiment, place_rules(services.settings)):
        return _full(request, visit.platform)
    client = client_address(request, services.settings)
    if found is None:  # a new row: counted against the client's arrivals this minute
        limit = PerMinute(services.engine, "arrival", services.settings.arrivals_per_minute, TooManyArrivalsError)
        limit.admit(client)
    arrival = found or arrivals.arrive(session, experiment, visit, client)
    return _consent_page(request, experiment, visit, recruiting, arrival)


def _consent_page(
    request: Request, experiment: ExperimentRecord, visit: PlatformVisit, recruiting: Recruitment, arrival: Any
) -> Response:
    """The consent page (``arrival`` None: MTurk's preview, which stores nothing and cannot be agreed to)."""
    return _page(
        request,
        "consent.html",
        visit.platform,
        experiment_id=experiment.id,
        consent=recruiting,
        arrival=arrival,
    )


def _declined(request: Request, arrival: Any, recruiting: Recruitment) -> Response:
    back = finish(
        arrival.platform, arrival.platform_session, arrival.submit_to, recruiting.no_consent_code, "no_consent"
    )
    return render(
        request,
        "study_message.html",
        secret_url=True,
        framed_by=MTURK_FRAME_ORIGINS if arrival.platform == "mturk" else (),
        posts_to=(back.origin,) if back is not None and back.fields else (),
        kind="declined",
        back=back,
        redirect_seconds=recruitment.REDIRECT_SECONDS,
    )


@router.post("/consent")
async def consent(request: Request, experiment_id: uuid.UUID, session: SessionDep, services: ServicesDep) -> Response:
    experiment = store.get_experiment(session, experiment_id)
    form = await read_form(request)
    arrival = arrivals.arrival_by_code(session, experiment.id, form.text("arrival", "", max_length=64))
    if arrival is None:
        raise InvalidFormError("This consent form is out of date: please open the study link again.")
    if arrival.participant is not None:  # a second click, or an old tab: they are in already
        return redirect(f"/p/{arrival.participant.code}")
    decision = form.text("decision", "", max_length=16)
    if decision not in ("agree", "decline"):
        raise InvalidFormError("Choose whether you agree to take part.", details={"field": "decision"})
    if arrival.consented is False or decision == "decline":
        arrivals.decline(session, arrival)
        return _declined(request, arrival, Recruitment.from_dict(experiment.recruitment))
    recruiting = Recruitment.from_dict(experiment.recruitment)
    _require_platform(recruiting, arrival.platform)
    if arrival.client_address is None:  # arrived before addresses were kept: the consent's own counts
        arrival.client_address = client_address(request, services.settings) or None
    try:
        participant = arrivals.admit(
            session, experiment, arrival, place_rules(services.settings), recruiting.places_per_client
        )
    except ClientHoldsPlacesError as exc:  # one address holds its places: the polite page, not a place
        busy = _page(request, "study_message.html", arrival.platform, status_code=429, kind="busy", back=None)
        busy.headers.update(exc.headers)
        return busy
    if participant is None:
        return _full(request, arrival.platform)
    return redirect(f"/p/{participant.code}")
