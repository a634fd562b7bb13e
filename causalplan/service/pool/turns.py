"""Whose turn a free planner worker is: interactive requests in arrival order, background work last.

``threading.Semaphore`` wakes whichever waiter the scheduler picks, and a background loop that
releases and re-acquires at once can take the worker again before a request that waited, so a
participant's first plan could wait behind hundreds of start-up drawings. Here each waiter has a
ticket: interactive tickets are served first come, first served; a background ticket (work
nobody waits for, such as the drawings made ahead at start) gets a worker only while no
interactive ticket waits, and at most ``background_workers`` of them work at once. So an
interactive request waits behind the requests that came before it and at most that many
background jobs.

A thread marks its work as background with ``with background():`` (a context variable: each
thread starts interactive).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

_background: ContextVar[bool] = ContextVar("causalplan_background_work", default=False)


@contextmanager
def background() -> Iterator[None]:
    """Mark the pool runs made inside as background work (they yield to every interactive request)."""
    token = _background.set(True)
    try:
        yield
    finally:
        _background.reset(token)


def is_background() -> bool:
    """Return whether the calling thread's runs are background work now."""
    return _background.get()


class Turns:
    """``size`` workers handed out by ticket: interactive first come, first served; background after them."""

    def __init__(self, size: int, background_workers: int = 1) -> None:
        self._condition = threading.Condition()
        self._free = size
        self._background_workers = background_workers
        self._background_busy = 0
        self._interactive: deque[object] = deque()
        self._waiting_background: deque[object] = deque()

    def take(self, timeout: float, is_background_work: bool) -> bool:
        """Wait up to ``timeout`` seconds for a worker; return whether one is now the caller's."""
        ticket = object()
        queue = self._waiting_background if is_background_work else self._interactive
        deadline = time.monotonic() + timeout
        with self._condition:
            queue.append(ticket)
            while not self._is_turn(ticket, is_background_work):
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    queue.remove(ticket)
                    self._condition.notify_all()  # the ticket behind this one may be first now
                    return False
                self._condition.wait(remaining)
            queue.popleft()
            self._free -= 1
            if is_background_work:
                self._background_busy += 1
            self._condition.notify_all()  # another worker may be free for the next ticket
            return True

    def give_back(self, is_background_work: bool) -> None:
        """Return a worker taken by ``take`` (with the same ``is_background_work``)."""
        with self._condition:
            self._free += 1
            if is_background_work:
                self._background_busy -= 1
            self._condition.notify_all()

    def waiting(self) -> tuple[int, int]:
        """Return the interactive and background tickets waiting."""
        with self._condition:
            return len(self._interactive), len(self._waiting_background)

    def _is_turn(self, ticket: object, is_background_work: bool) -> bool:
        if self._free <= 0:
            return False
        if not is_background_work:
            return self._interactive[0] is ticket
        return (
            not self._interactive
            and self._background_busy < self._background_workers
            and self._waiting_background[0] is ticket
        )
