"""How an arrival is assigned to a condition: the open condition with the fewest places taken.

Each condition of an experiment has places on the public link (a quota, or none). The service
reads them, asks ``choose`` which to take, and takes it atomically (``service/storage/arrivals``);
the participant's number within the condition then picks their object orders (``counterbalance``).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Place:
    """One condition's places on the public link."""

    condition: str
    taken: int
    quota: int | None

    @property
    def is_open(self) -> bool:
        return self.quota is None or self.taken < self.quota


def choose(found: list[Place]) -> Place | None:
    """Return the open place with the fewest taken (ties: the condition defined first); None when all are full."""
    open_places = [place for place in found if place.is_open]
    return min(open_places, key=lambda place: place.taken) if open_places else None
