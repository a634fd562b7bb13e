"""What every participant page shares: the journey of the code in the address, and how a page is sent."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import Depends, Path, Request, Response

from causalplan.service.deps import CatalogDep, SessionDep
from causalplan.service.pages.templating import redirect, render
from causalplan.service.storage import experiments as store
from causalplan.service.storage.experiments import ParticipantJourney
from causalplan.studies.recruitment import MTURK_FRAME_ORIGINS

Code = Annotated[str, Path(max_length=64)]
Number = Annotated[int, Path(ge=1, le=100)]


def get_journey(code: Code, session: SessionDep, catalog: CatalogDep) -> ParticipantJourney:
    return ParticipantJourney.of(store.participant_by_code(session, code), catalog)


JourneyDep = Annotated[ParticipantJourney, Depends(get_journey)]


def here(journey: ParticipantJourney) -> Response:
    return redirect(f"/p/{journey.participant.code}/{journey.current_page()}")


def common(journey: ParticipantJourney) -> dict[str, Any]:
    """Return what every participant page shows: the code, where they are, the steps and objects."""
    return {
        "code": journey.participant.code,
        "journey": journey,
        "stage": journey.stage.value,
        "goal": journey.goal,
        "training": journey.training,
        "tests": journey.tests,
    }


def framing(journey: ParticipantJourney) -> tuple[str, ...]:
    """Return the origins that may frame the participant's pages (MTurk's, for MTurk workers)."""
    arrival = journey.participant.arrival
    return MTURK_FRAME_ORIGINS if arrival is not None and arrival.platform == "mturk" else ()


def page(
    request: Request, journey: ParticipantJourney, template: str, status_code: int = 200, **context: Any
) -> Response:
    """Return one of the participant's pages (secret address; framed by their platform when it must be)."""
    return render(
        request,
        template,
        secret_url=True,
        status_code=status_code,
        framed_by=framing(journey),
        **common(journey),
        **context,
    )
