"""Failed research-token attempts per client address: after too many in a window, refuse the next ones.

``FailedAttempts.check`` compares a token only while its address has fewer than ``max_failures``
failures in the last ``window_seconds``; otherwise it raises ``TooManyAttemptsError`` (429,
``Retry-After``) without comparing, so a right guess during a lockout is refused too.
Successes are not counted. Memory stays bounded: each address keeps at most ``max_failures``
times, addresses whose failures have all left the window are dropped, and at most
``max_addresses`` are tracked (the one that failed least recently is dropped first).
"""

from __future__ import annotations

import math
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable

from causalplan.service.errors import TooManyAttemptsError

MAX_ADDRESSES = 10_000
"""Client addresses tracked at once (each holds at most ``max_failures`` floats)."""


class FailedAttempts:
    """Recent failed attempts by client address, in a sliding window; safe to share between threads."""

    def __init__(
        self,
        max_failures: int,
        window_seconds: float,
        max_addresses: int = MAX_ADDRESSES,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if max_failures < 1 or window_seconds <= 0 or max_addresses < 1:
            raise ValueError("max_failures, window_seconds and max_addresses must be positive")
        self.max_failures = max_failures
        self.window_seconds = window_seconds
        self.max_addresses = max_addresses
        self._clock = clock
        # Ordered by each address's latest failure, oldest first: what expires or is evicted first.
        self._failures: OrderedDict[str, deque[float]] = OrderedDict()
        self._lock = threading.Lock()

    def check(self, address: str, is_correct: Callable[[], bool]) -> bool:
        """Return ``is_correct()``, counting False as a failure of ``address``.

        Raises ``TooManyAttemptsError`` instead, without calling ``is_correct``, while ``address``
        has ``max_failures`` failures in the window.
        """
        # The comparison runs under the lock, so concurrent guesses cannot overshoot the limit.
        with self._lock:
            now = self._clock()
            self._forget_expired(now)
            failures = self._failures.get(address)
            if failures is not None:
                while failures[0] <= now - self.window_seconds:
                    failures.popleft()  # never empties: the address's latest failure is in the window
                if len(failures) >= self.max_failures:
                    wait = max(1, math.ceil(failures[0] + self.window_seconds - now))
                    raise TooManyAttemptsError(
                        f"Too many wrong tokens from this address: try again in {wait} s.", retry_after=wait
                    )
            if is_correct():
                return True
            if failures is None:
                failures = self._failures[address] = deque(maxlen=self.max_failures)
                if len(self._failures) > self.max_addresses:
                    self._failures.popitem(last=False)
            else:
                self._failures.move_to_end(address)
            failures.append(now)
            return False

    def __len__(self) -> int:
        """Return how many addresses have failures on record (some may have left the window since)."""
        with self._lock:
            return len(self._failures)

    def _forget_expired(self, now: float) -> None:
        while self._failures:
            address, failures = next(iter(self._failures.items()))
            if failures[-1] > now - self.window_seconds:
                return
            del self._failures[address]
