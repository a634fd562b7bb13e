"""What the web pages do beside requests, in one background thread for the app's life.

At start and then periodically: purge the demo participants left alone too long, the arrivals
on public study links that never decided on consent (``undecided_arrival_hours``), the invalid
models of ``POST /v1/models`` that no trial uses (``invalid_model_hours``), the models and
trials of clients without a key (``anonymous_record_hours``, the space given back), and forget the
revocations of research cookies that have lapsed anyway. Once, after start: draw the pictures
of the catalog objects' likely plans (``ahead``), as background work of the planner pool (a
request waits behind one drawing at most). The thread starts after the service is up, so none
of this delays start-up.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import timedelta

import anyio
from fastapi import FastAPI

from causalplan.errors import CausalPlanError
from causalplan.service.deps import Services, open_session
from causalplan.service.pages import ahead
from causalplan.service.storage.arrivals import purge_undecided
from causalplan.service.storage.crud import purge_expired_records, purge_invalid_models
from causalplan.service.storage.demo import DemoStarts, purge_demo_participants
from causalplan.service.storage.records import utc_now
from causalplan.service.storage.revocations import forget_lapsed_revocations
from causalplan.service.work.calls import in_background

logger = logging.getLogger(__name__)

LONGEST_PURGE_INTERVAL_SECONDS = 3600.0
"""The purge runs at least this often, and four times per (shortest) retention period when that is shorter."""
FIRST_OBJECTS = ("desk_lamp", "flashlight")
"""Drawn ahead first: the demo's training objects."""


def purge_interval(services: Services) -> float:
    """Return the seconds between two purges."""
    settings = services.settings
    shortest = min(
        settings.demo_retention_hours,
        settings.undecided_arrival_hours,
        settings.invalid_model_hours,
        settings.anonymous_record_hours,
    )
    return min(LONGEST_PURGE_INTERVAL_SECONDS, shortest * 3600 / 4)


def purge(services: Services) -> int:
    """Purge old demo participants, undecided arrivals, unused invalid models, expired rows and lapsed revocations.

    Return the demo participants purged.
    """
    now = utc_now()
    settings = services.settings
    with open_session(services) as session:
        purged = purge_demo_participants(session, now - timedelta(hours=settings.demo_retention_hours))
        arrivals = purge_undecided(session, now - timedelta(hours=settings.undecided_arrival_hours))
        models = purge_invalid_models(session, now - timedelta(hours=settings.invalid_model_hours))
        forget_lapsed_revocations(session, now)
    expired = purge_expired_records(services.engine, now)  # and gives the space back
    if purged or arrivals or models or expired:
        logger.info(
            "purged %d demo participants, %d undecided arrivals, %d invalid models, %d expired models and trials",
            purged,
            arrivals,
            models,
            expired,
        )
    return purged


class Upkeep:
    """The background thread: purges at start and every ``purge_interval``, and draws plans ahead once."""

    def __init__(self, services: Services) -> None:
        self.services = services
        self.stop = threading.Event()
        self.purges = 0
        """Purges finished (a test waits for the first)."""
        self.drawn_ahead: int | None = None
        """Pictures drawn ahead, once that is done (None before)."""
        self._thread = threading.Thread(target=self._run, name="causalplan-web-upkeep", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def close(self, timeout: float) -> None:
        """Ask the thread to stop and wait up to ``timeout`` s (a picture being drawn is finished first)."""
        self.stop.set()
        self._thread.join(timeout)

    def _purge(self) -> None:
        try:
            purge(self.services)
        except CausalPlanError as exc:  # the database is away: try again next time
            logger.warning("demo purge failed: %s", exc.message)
        self.purges += 1

    def _run(self) -> None:
        self._purge()
        if self.services.settings.draw_plans_ahead:
            objects = sorted(self.services.catalog.objects.values(), key=lambda o: (o.id not in FIRST_OBJECTS, o.id))
            with in_background():  # a request never waits behind more than one of these drawings
                self.drawn_ahead = ahead.draw_ahead(self.services, objects, self.stop)
        while not self.stop.wait(purge_interval(self.services)):
            self._purge()


@asynccontextmanager
async def lifespan(app: FastAPI) -> AsyncIterator[None]:
    """Run inside the app's own lifespan (its services are up): the demo's start limit and the upkeep thread."""
    services: Services = app.state.services
    app.state.demo_starts = DemoStarts(services.engine, services.settings.demo_starts_per_minute)
    upkeep = Upkeep(services)
    app.state.upkeep = upkeep
    upkeep.start()
    try:
        yield
    finally:
        await anyio.to_thread.run_sync(upkeep.close, 30.0)
