"""Limits every replica shares, kept in the database: wrong research tokens, and counts per fixed window.

``FailedAttempts.check`` accepts a right token from any address at any time: wrong tokens cost
only their sender. A wrong one is counted against its client (its address); once the client has
``max_failures`` failures in the last ``window_seconds``, or all clients together ``max_total``,
its further wrong tokens get ``TooManyAttemptsError`` (429, ``Retry-After``) instead of 401, and
are not stored (a client at its limit adds no rows). Successes are not counted. Tokens are long
(API keys have 16+ characters), so guessing stays hopeless without refusing right ones.

``WindowCounter.admit`` counts one event of a client in the current fixed window and says
whether the window still had room; ``PerMinute`` raises a 429 error when it had not (demo
starts, arrivals on a public study link, stored models).

Both live in tables (``failed_attempts``, ``window_counts``) rather than in process memory, so
several ``causalplan serve`` replicas behind a load balancer hold one count: a guesser cannot
multiply the limit by the number of replicas. Times are seconds since the epoch (every
replica's clock reads the same). The tables stay small: rows that have left their window are
deleted as new ones come, and a client at its limit adds no more rows.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, cast

from sqlalchemy import CursorResult, Engine, and_, delete, func, insert, select, text, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from causalplan.inputs import clean_text
from causalplan.service.errors import TooManyAttemptsError, TryLaterError
from causalplan.service.storage.crud import storage_errors
from causalplan.service.storage.records import MAX_CLIENT_ID_LENGTH, FailedAttemptRecord, WindowCountRecord

_THROTTLE_LOCK_ID = 0x74687274
"""PostgreSQL advisory lock held while one replica checks a token: guesses on many replicas queue up."""


def _client_key(client: str) -> str:
    return clean_text(client)[:MAX_CLIENT_ID_LENGTH]


@contextmanager
def _locked_session(engine: Engine, lock_id: int) -> Iterator[Session]:
    """Yield a session in a transaction that holds ``lock_id`` on PostgreSQL until it ends.

    On SQLite (one machine) the caller's thread lock is enough: SQLite is not for replicas.
    """
    with Session(engine) as session, storage_errors(session):
        if engine.dialect.name == "postgresql":
            session.execute(text("SELECT pg_advisory_xact_lock(:id)"), {"id": lock_id})
        yield session
        session.commit()


class FailedAttempts:
    """Recent failed attempts by client and in total, in a sliding window, stored in the database."""

    def __init__(
        self,
        engine: Engine,
        max_failures: int,
        window_seconds: float,
        max_total: int,
        clock: Callable[[], float] = time.time,
    ) -> None:
        if min(max_failures, max_total) < 1 or window_seconds <= 0:
            raise ValueError("max_failures, max_total and window_seconds must be positive")
        self.engine = engine
        self.max_failures = max_failures
        self.max_total = max_total
        self.window_seconds = window_seconds
        self._clock = clock
        self._lock = threading.Lock()

    def _wait(self, session: Session, client: str | None, limit: int, now: float) -> int | None:
        """Return the seconds until ``client``'s failures (all, for None) are under ``limit``; None if they are."""
        since = now - self.window_seconds
        recent = select(FailedAttemptRecord.at).where(FailedAttemptRecord.at > since)
        if client is not None:
            recent = recent.where(FailedAttemptRecord.client == client)
        # The limit-th newest failure is the one that must leave the window before the next attempt.
        times = session.scalars(recent.order_by(FailedAttemptRecord.at.desc()).limit(limit)).all()
        if len(times) < limit:
            return None
        return max(1, math.ceil(times[-1] + self.window_seconds - now))

    def check(self, client: str, is_correct: Callable[[], bool]) -> bool:
        """Return ``is_correct()``, counting False as a failure of ``client``.

        A right token is accepted whatever the counts (no database work). A wrong one raises
        ``TooManyAttemptsError`` instead of returning False while ``client``, or all clients
        together, are at their limit in the window.
        """
        if is_correct():
            return True
        client = _client_key(client)
        # Counted under the locks, so concurrent wrong guesses cannot overshoot the limits.
        with self._lock, _locked_session(self.engine, _THROTTLE_LOCK_ID) as session:
            now = self._clock()
            wait = self._wait(session, client, self.max_failures, now)
            if wait is not None:
                raise TooManyAttemptsError(f"Too many wrong tokens from this address: try again in {wait} s.", wait)
            wait = self._wait(session, None, self.max_total, now)
            if wait is not None:
                raise TooManyAttemptsError(f"Too many wrong tokens lately: try again in {wait} s.", wait)
            session.execute(delete(FailedAttemptRecord).where(FailedAttemptRecord.at <= now - self.window_seconds))
            session.add(FailedAttemptRecord(client=client, at=now))
            return False

    def __len__(self) -> int:
        """Return how many clients have failures in the window."""
        since = self._clock() - self.window_seconds
        with Session(self.engine) as session, storage_errors(session):
            clients = select(func.count(func.distinct(FailedAttemptRecord.client))).where(
                FailedAttemptRecord.at > since
            )
            return session.scalar(clients) or 0


class WindowCounter:
    """Counts events of each client in fixed windows of ``window_seconds``, at most ``per_window`` each."""

    def __init__(
        self,
        engine: Engine,
        scope: str,
        per_window: int,
        window_seconds: float,
        clock: Callable[[], float] = time.time,
    ) -> None:
        self.engine = engine
        self.scope = scope
        self.per_window = per_window
        self.window_seconds = window_seconds
        self._clock = clock

    def admit(self, client: str) -> tuple[int, int] | None:
        """Count one event of ``client``; None when admitted, else (events so far, seconds until the next window).

        The count goes up by one only while it is under ``per_window``, in one statement, so
        replicas counting at once never admit more than the limit.
        """
        client = _client_key(client)
        while True:  # another replica may count this client between two of our statements: count again
            now = self._clock()
            window = math.floor(now / self.window_seconds)
            ends_at = (window + 1) * self.window_seconds
            key = and_(
                WindowCountRecord.scope == self.scope,
                WindowCountRecord.client == client,
                WindowCountRecord.window == window,
            )
            with Session(self.engine) as session, storage_errors(session):
                increment = session.execute(
                    update(WindowCountRecord)
                    .where(key, WindowCountRecord.count < self.per_window)
                    .values(count=WindowCountRecord.count + 1)
                )
                if cast(CursorResult[Any], increment).rowcount:
                    session.commit()
                    return None
                existing = session.scalar(select(WindowCountRecord.count).where(key))
                if existing is not None and existing >= self.per_window:
                    session.commit()
                    return existing, max(1, math.ceil(ends_at - now))
                if existing is None:  # this client's first event in the window
                    session.execute(delete(WindowCountRecord).where(WindowCountRecord.ends_at <= now))
                    try:
                        with session.begin_nested():
                            session.execute(
                                insert(WindowCountRecord).values(
                                    scope=self.scope, client=client, window=window, count=1, ends_at=ends_at
                                )
                            )
                    except IntegrityError:  # another replica counted this client's first event just now
                        session.commit()
                        continue
                    session.commit()
                    return None
                session.commit()  # under the limit: counted by another replica between our update and read


MINUTE_SECONDS = 60.0
"""``PerMinute`` counts each client's events in fixed windows this long."""


class PerMinute:
    """At most ``per_minute`` events of each client a minute (0: no limit); beyond, ``refuse`` makes the 429 error."""

    def __init__(
        self,
        engine: Engine,
        scope: str,
        per_minute: int,
        refuse: Callable[[str, int], TryLaterError],
        clock: Callable[[], float] = time.time,
    ) -> None:
        self.per_minute = per_minute
        self._refuse = refuse
        self._counter = WindowCounter(engine, scope, max(per_minute, 1), MINUTE_SECONDS, clock)

    def message(self, count: int, retry_after: int) -> str:
        """Return what the 429 error says to a client with ``count`` events this minute."""
        return f"Too many at once from this address ({count} in a minute): wait {retry_after} s."

    def admit(self, client: str) -> None:
        """Count one event of ``client``; raise ``refuse(message, seconds)`` when its minute is full."""
        if self.per_minute == 0:
            return
        refused = self._counter.admit(client)
        if refused is not None:
            count, retry_after = refused
            raise self._refuse(self.message(count, retry_after), retry_after)
