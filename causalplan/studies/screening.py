"""Screening participants: the comprehension check's rule and the too-fast flag, each an exclusion with its reason.

The service stores each exclusion as a record of its own, never deleted; the export
gives every participant ``excluded`` and ``exclusion_reason``, which ``causalplan analyze`` honours.
"""

from __future__ import annotations

from dataclasses import dataclass

from causalplan.studies.journey import Journey
from causalplan.studies.steps import Stage


@dataclass(frozen=True)
class Exclusion:
    """Why a participant is screened out: a short ``reason`` code and the ``detail`` in words."""

    reason: str
    detail: str


def comprehension_try(journey: Journey, answers: dict[str, str], all_correct: bool) -> Exclusion | None:
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
    return Exclusion("comprehension", f"not every comprehension question right within {tries} tries")


def too_fast(journey: Journey) -> Exclusion | None:
    """Return the exclusion of a participant who has just finished faster than the experiment allows (else None)."""
    seconds = journey.seconds_taken()
    threshold = journey.recruitment.too_fast_seconds
    if journey.stage is not Stage.DONE or seconds is None or threshold is None or seconds >= threshold:
        return None
    return Exclusion("too_fast", f"finished in {seconds:.0f} s; the threshold is {threshold} s")
