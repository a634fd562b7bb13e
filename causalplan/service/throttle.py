"""Failed research-token attempts, per client and in total: after too many in a window, refuse the next ones.

``FailedAttempts.check`` compares a token only while its client has fewer than ``max_failures``
failures in the last ``window_seconds`` and all clients together fewer than ``max_total``;
otherwise it raises ``TooManyAttemptsError`` (429, ``Retry-After``) without comparing, so a
right guess during a lockout is refused too. Successes are not counted. Memory stays bounded:
each client keeps at most ``max_failures`` times, the total at most ``max_total``, and at most
``max_clients`` clients are tracked (``cachetools.TTLCache``: the least recently failed goes
first, and a client whose last failure has left the window is forgotten).
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable

from cachetools import TTLCache

from causalplan.service.errors import TooManyAttemptsError

MAX_CLIENTS = 10_000
"""Clients tracked at once (each holds at most ``max_failures`` floats)."""


class FailedAttempts:
    """Recent failed attempts by client and in total, in a sliding window; safe to share between threads."""

    def __init__(
        self,
        max_failures: int,
        window_seconds: float,
        max_total: int,
        max_clients: int = MAX_CLIENTS,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if min(max_failures, max_total, max_clients) < 1 or window_seconds <= 0:
            raise ValueError("max_failures, max_total, max_clients and window_seconds must be positive")
        self.max_failures = max_failures
        self.max_total = max_total
        self.window_seconds = window_seconds
        self._clock = clock
        self._clients: TTLCache[str, deque[float]] = TTLCache(maxsize=max_clients, ttl=window_seconds, timer=clock)
        self._total: deque[float] = deque(maxlen=max_total)
        self._lock = threading.Lock()

    def _wait(self, failures: deque[float], limit: int, now: float) -> int | None:
        """Return the seconds until ``failures`` (times, oldest first) is under ``limit`` again; None if it is."""
        while failures and failures[0] <= now - self.window_seconds:
            failures.popleft()
        if len(failures) < limit:
            return None
        return max(1, math.ceil(failures[0] + self.window_seconds - now))

    def check(self, client: str, is_correct: Callable[[], bool]) -> bool:
        """Return ``is_correct()``, counting False as a failure of ``client``.

        Raises ``TooManyAttemptsError`` instead, without calling ``is_correct``, while ``client``
        or all clients together are at their limit in the window.
        """
        # The comparison runs under the lock, so concurrent guesses cannot overshoot the limits.
        with self._lock:
            now = self._clock()
            failures = self._clients.get(client)
            wait = self._wait(failures, self.max_failures, now) if failures is not None else None
            if wait is not None:
                raise TooManyAttemptsError(f"Too many wrong tokens from this address: try again in {wait} s.", wait)
            wait = self._wait(self._total, self.max_total, now)
            if wait is not None:
                raise TooManyAttemptsError(f"Too many wrong tokens lately: try again in {wait} s.", wait)
            if is_correct():
                return True
            failures = failures if failures is not None else deque(maxlen=self.max_failures)
            failures.append(now)
            self._clients[client] = failures  # set again: its window starts from this failure
            self._total.append(now)
            return False

    def __len__(self) -> int:
        """Return how many clients have failures in the window."""
        with self._lock:
            self._clients.expire()
            return len(self._clients)
