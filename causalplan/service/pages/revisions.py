"""The names of a participant's drafts, each saved with a revision, and the revision a form carries.

Every box (or group of boxes saved together) has a key; each save of it carries the page's
revision stamp, which only grows, and the server keeps the newest (``Journey.accept_revision``).
So a late request, a request resent after a reload, or an old form posted again never
overwrites text saved after it.
"""

from __future__ import annotations

from causalplan.service.errors import InvalidFormError
from causalplan.service.pages.forms import Form
from causalplan.service.storage.experiments import ParticipantJourney
from causalplan.studies.steps import Stage

TUTORIAL_ANSWERS = "tutorial:answers"
TUTORIAL_RULES = "tutorial:rules"
STEP2_RULES = "step2:rules"
MAX_REVISION = 2**53
"""The largest revision a page may send (JavaScript's largest exact integer)."""


def functions_key(object_id: str) -> str:
    """Return the key of step 1's boxes of one training object."""
    return f"step1:{object_id}"


def mapping_key(object_id: str) -> str:
    """Return the key of step 3's choices for one test object."""
    return f"step3:{object_id}"


def form_revision(form: Form) -> int | None:
    """Return the revision a page's form carries (None: posted without the script, or an empty field)."""
    text = form.text("revision", "", max_length=20).strip()
    if not text:
        return None
    if not text.isdigit() or int(text) > MAX_REVISION:
        raise InvalidFormError(
            f"The form's 'revision' must be a whole number from 0 to {MAX_REVISION}.", details={"field": "revision"}
        )
    return int(text)


def save_rules(journey: ParticipantJourney, text: str, revision: int | None, practice: bool = False) -> bool:
    """Save the rule box (the tutorial's when ``practice``) unless newer rules are stored; return whether saved."""
    if practice:
        journey.require_open(Stage.TUTORIAL)
        if not journey.accept_revision(TUTORIAL_RULES, revision):
            return False
        journey.save_tutorial(rules=text)
        return True
    journey.require_open(Stage.STEP2)
    if not journey.accept_revision(STEP2_RULES, revision):
        return False
    journey.save_rules(text)
    return True
