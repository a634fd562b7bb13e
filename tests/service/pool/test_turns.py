"""Whose turn a free worker is: interactive requests in arrival order, background work only when none waits."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from causalplan.service.pool.pool import PlannerPool
from causalplan.service.pool.turns import Turns, background, is_background
from tests.service.fixtures import settings_for, wait_until
from tests.service.pool.jobs_for_tests import timed_sleep


class Waiter:
    """A thread that takes a turn, records it, and keeps it until told to give it back."""

    def __init__(self, turns: Turns, name: str, served: list[str], is_background_work: bool = False) -> None:
        self.turns = turns
        self.name = name
        self.served = served
        self.is_background_work = is_background_work
        self.has_turn = threading.Event()
        self.done = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        assert self.turns.take(30.0, self.is_background_work)
        self.served.append(self.name)
        self.has_turn.set()
        self.done.wait(30.0)
        self.turns.give_back(self.is_background_work)

    def start_waiting(self, waiting: Callable[[], bool]) -> Waiter:
        """Start the thread; return once ``waiting()`` shows its ticket in the line."""
        self.thread.start()
        wait_until(waiting)
        return self

    def finish(self) -> None:
        self.done.set()
        self.thread.join(30.0)


def test_waiters_are_served_in_the_order_they_came() -> None:
    turns = Turns(1)
    assert turns.take(1.0, False)
    served: list[str] = []
    waiters = [
        Waiter(turns, f"request-{index}", served).start_waiting(lambda index=index: turns.waiting()[0] == index + 1)
        for index in range(6)
    ]
    turns.give_back(False)
    for waiter in waiters:
        assert waiter.has_turn.wait(30.0)
        waiter.finish()
    assert served == [f"request-{index}" for index in range(6)]


def test_background_work_waits_until_no_request_does() -> None:
    turns = Turns(1)
    assert turns.take(1.0, False)
    served: list[str] = []
    drawing = Waiter(turns, "drawing", served, True).start_waiting(lambda: turns.waiting() == (0, 1))
    request = Waiter(turns, "request", served).start_waiting(lambda: turns.waiting() == (1, 1))
    turns.give_back(False)
    assert request.has_turn.wait(30.0)
    assert not drawing.has_turn.is_set()  # it came first, but a request waited
    request.finish()
    assert drawing.has_turn.wait(30.0)
    drawing.finish()
    assert served == ["request", "drawing"]


def test_one_background_job_at_a_time_leaves_the_other_workers_to_requests() -> None:
    turns = Turns(2)
    assert turns.take(1.0, True)
    assert not turns.take(0.05, True)  # a worker is free, but one drawing works already
    assert turns.waiting() == (0, 0)  # the ticket that gave up left the line
    assert turns.take(0.05, False)


def test_a_waiter_that_gives_up_lets_the_next_one_through() -> None:
    turns = Turns(1)
    assert turns.take(1.0, False)
    assert not turns.take(0.05, False)
    served: list[str] = []
    later = Waiter(turns, "later", served).start_waiting(lambda: turns.waiting()[0] == 1)
    turns.give_back(False)
    assert later.has_turn.wait(30.0)
    later.finish()


def test_background_marks_only_the_calls_made_inside_it() -> None:
    assert not is_background()
    with background():
        assert is_background()
        seen: list[bool] = []
        thread = threading.Thread(target=lambda: seen.append(is_background()))
        thread.start()
        thread.join()
        assert seen == [False]  # another thread starts interactive
    assert not is_background()


def test_a_request_waits_behind_one_drawing_at_most_in_a_real_pool() -> None:
    """A background loop re-asks at once after each job; a request made meanwhile is next, not last."""
    pool = PlannerPool(1, 8, settings_for("sqlite://").worker_memory_mb, queue_wait_seconds=60.0)
    pool.start()
    drawings: list[tuple[float, float, int]] = []
    stop = threading.Event()
    first_done = threading.Event()

    def draw_ahead() -> None:
        with background():
            for _ in range(50):  # bounded: the test stops it long before
                if stop.is_set():
                    return
                drawings.append(pool.run(timed_sleep, (0.1,), 30.0))
                first_done.set()

    drawer = threading.Thread(target=draw_ahead, daemon=True)
    try:
        drawer.start()
        assert first_done.wait(60.0)
        asked = time.monotonic()
        began, _, _ = pool.run(timed_sleep, (0.0,), 30.0)
        stop.set()
        drawer.join(60.0)
    finally:
        stop.set()
        pool.close()
    waited_behind = [drawing for drawing in drawings if drawing[0] < began and drawing[1] > asked]
    assert len(waited_behind) <= 1, waited_behind  # the one at work when it asked (or taking its turn then)
