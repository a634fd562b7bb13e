"""How an arrival is assigned to a condition: the open condition with the fewest places held.

Each condition of an experiment has places on the public link (a quota, or none). A place is
held by a participant who finished, or who is still at work: admitted a short while ago, or
changed their work lately. An admitted person who never starts, or stops for long, lets their
place go (a bot that agrees and leaves cannot keep the study full). The quota counts finished
participants; while they are under it, up to ``PlaceRules.extra`` more than the quota may be
at work at once (some of them will not finish), and never more.

The service reads the places, asks ``choose`` which to take, and takes it atomically
(``service/storage/arrivals``); the participant's number within the condition (``admitted``,
every admission so far) then picks their object orders (``counterbalance``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import timedelta


@dataclass(frozen=True)
class PlaceRules:
    """How long an admitted participant holds a place, and how far beyond the quota the link admits."""

    start_minutes: float = 15.0
    """An admitted participant who has saved nothing yet holds a place this long after admission."""
    hold_hours: float = 3.0
    """One who started holds it this long after their last change (or until they finish)."""
    over_admission: float = 0.1
    """Fraction of the quota (rounded down) admitted beyond it while completions are under it."""

    def extra(self, quota: int) -> int:
        """Return how many more than ``quota`` may be at work at once."""
        return math.floor(quota * self.over_admission)

    @property
    def start(self) -> timedelta:
        return timedelta(minutes=self.start_minutes)

    @property
    def hold(self) -> timedelta:
        return timedelta(hours=self.hold_hours)


@dataclass(frozen=True)
class Place:
    """One condition's places on the public link."""

    condition: str
    taken: int
    """Places held: finished participants and those still at work."""
    quota: int | None
    finished: int = 0
    """Participants who completed the study (what the quota counts)."""
    extra: int = 0
    """How many more than the quota may be at work at once (``PlaceRules.extra``)."""
    admitted: int | None = None
    """Every admission so far, the next participant's number (None: ``taken``)."""

    @property
    def number(self) -> int:
        """Return the next admitted participant's number within the condition."""
        return self.taken if self.admitted is None else self.admitted

    @property
    def is_open(self) -> bool:
        return self.quota is None or (self.finished < self.quota and self.taken < self.quota + self.extra)


def choose(found: list[Place]) -> Place | None:
    """Return the open place with the fewest held (ties: the condition defined first); None when all are full.

    A condition whose quota is met (in completions) closes while some of its admitted are still
    at work; another condition of the same quota, a few completions behind, would otherwise
    take every later arrival up to its over-admission and end several completions ahead. So no
    condition takes a place that puts it more than one ahead of a condition of the same quota
    that has met it.
    """
    open_places = [place for place in found if place.is_open and not _runs_ahead(place, found)]
    return min(open_places, key=lambda place: place.taken) if open_places else None


def _runs_ahead(place: Place, found: list[Place]) -> bool:
    """Return whether one more place would put ``place`` two ahead of a condition of its quota that met it."""
    return any(
        other is not place
        and other.quota is not None
        and other.quota == place.quota
        and other.finished >= other.quota
        and place.taken > other.taken
        for other in found
    )
