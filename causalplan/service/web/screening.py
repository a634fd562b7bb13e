"""Screening participants: the comprehension check's rule and the too-fast flag, each an exclusion with its reason.

An exclusion is a record of its own (``participant_exclusions``), never deleted; the export
gives every participant ``excluded`` and ``exclusion_reason``, which ``causalplan analyze`` honours.
"""

from __future__ import annotations

from causalplan.service.db.models import ExclusionRecord
from causalplan.service.web.arrivals import exclusion
from causalplan.service.web.journey import Journey
from causalplan.service.web.study import Stage


def comprehension_try(journey: Journey, answers: dict[str, str], all_correct: bool) -> ExclusionRecord | None:
    """Count one try of the comprehension check; screen out and return the exclusion when the rule says so.

    The rule: every question right within the experiment's ``comprehension_tries`` (None: no rule).
    Once passed, later tries (to fix the practice rules) no longer count.
    """
    if journey.has_passed_comprehension():
        return None
    tries = journey.record_tutorial_try(answers, all_correct)
    limit = journey.recruitment.comprehension_tries
    if all_correct or limit is None or tries < limit:
        return None
    journey.screen_out()
    return exclusion(
        journey.participant, "comprehension", f"not every comprehension question right within {tries} tries"
    )


def too_fast(journey: Journey) -> ExclusionRecord | None:
    """Return the exclusion of a participant who has just finished faster than the experiment allows (else None)."""
    seconds = journey.seconds_taken()
    threshold = journey.recruitment.too_fast_seconds
    if journey.stage is not Stage.DONE or seconds is None or threshold is None or seconds >= threshold:
        return None
    return exclusion(journey.participant, "too_fast", f"finished in {seconds:.0f} s; the threshold is {threshold} s")
