"""POST /p/<code>/explain: step 2's "Why?" beside each step of the robot's plan and its "Why not…?" box.

The participant's draft model (as ``/plan`` plans it) is explained on one training object:
``causalplan explain`` in a planner worker, answered in words. Step 2 only: participants in
the test phase never see explanations or repairs.
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter
from pydantic import Field

from causalplan.service.api.schemas.common import InputModel, OutputModel
from causalplan.service.api.schemas.experiments import MAX_RULES_TEXT
from causalplan.service.deps import CatalogDep, ServicesDep, SettingsDep
from causalplan.service.documents import default_planner
from causalplan.service.errors import InvalidRequestError, NotFoundError
from causalplan.service.pages.journeys import JourneyDep
from causalplan.service.pages.participation import invalid_model_error
from causalplan.service.work.planning import ExplanationArguments
from causalplan.service.work.registry import EXPLANATION
from causalplan.studies.steps import Stage, check_model, model_on

router = APIRouter(prefix="/p/{code}", include_in_schema=False)


class ExplainIn(InputModel):
    """One question about the plan on one training object: ``why`` a step (its number), or ``why_not``."""

    object: str = Field(max_length=64)
    why: str | None = Field(default=None, max_length=8)
    why_not: str | None = Field(default=None, max_length=200)
    rules: str | None = Field(
        default=None,
        max_length=MAX_RULES_TEXT,
        description="The rules of the plan on screen (default: the rules saved); the answer is about that plan.",
    )


class ExplainOut(OutputModel):
    """The answer in words; for a why-not question the alternative plan's steps (none when there is none).

    A question the robot did not understand is refused (422) with ``details["suggestions"]``: the
    closest questions it can answer, in the object's words, for the page to offer as buttons.
    """

    answer: str
    code: str | None
    alternative: list[str]


@router.post("/explain", response_model=ExplainOut)
def explain(
    body: ExplainIn, journey: JourneyDep, services: ServicesDep, catalog: CatalogDep, settings: SettingsDep
) -> ExplainOut:
    """Explain the robot's plan of the draft model on one training object, in words."""
    journey.require_open(Stage.STEP2)
    obj = next((o for o in journey.training if o.id == body.object), None)
    if obj is None:
        raise NotFoundError(f"'{body.object}' is not one of your objects.")
    if (body.why is None) == (body.why_not is None):
        raise InvalidRequestError("Ask one question: 'why' (a step number) or 'why_not'.")
    draft = journey.draft_model(body.rules)  # the plan on screen, which the rule box may have moved on from
    check = check_model(draft, catalog, settings)
    if not check.is_valid:
        raise invalid_model_error(check)
    model, limit = model_on(draft, obj.id), settings.default_time_limit
    arguments = ExplanationArguments(model, None, default_planner(), limit, body.why, body.why_not)
    data: dict[str, Any] = services.work.run(EXPLANATION, arguments)
    contrast = data.get("why_not")
    if contrast is not None:
        unchanged = contrast["code"] in ("already_does", "is_base")  # no other plan to show
        steps = [] if unchanged else (contrast["alternative"].get("plan") or [])
        return ExplainOut(answer=contrast["message"], code=contrast["code"], alternative=[s["text"] for s in steps])
    return ExplainOut(answer=" ".join(why["message"] for why in data["why"]), code=None, alternative=[])
