"""The planner pool: warm worker processes behind a queue limit, run by ``pebble``.

``pebble.ProcessPool`` starts the workers (forked from a fork server, never from the app,
which runs uvicorn's and anyio's threads), kills the one whose call overruns its time limit or
is cancelled, fails only that call, and replaces the worker. What it cannot do is kept here,
each for its reason:

- the in-flight cap and the wait for a free worker: pebble queues without limit (and runs in
  its own order; ``turns.Turns`` serves interactive requests in arrival order, background work last);
- the workers' hello and "started" messages (``worker.run_call``): pebble does not say which
  worker runs a call, and a cancelled call's caller waits until that worker is dead;
- a new pebble pool when a worker dies while none is working: pebble then takes the whole pool
  for broken (its sign of a failing initializer), and every later call would fail;
- failing the calls still running when the pool closes: pebble leaves their futures unresolved.

``PlannerPool.run`` blocks the calling thread (a route's worker thread, never the event loop).
"""

from __future__ import annotations

import itertools
import logging
import math
import multiprocessing
import os
import threading
import time
from collections.abc import Callable
from concurrent.futures import CancelledError, Future, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import Any, TypeVar

from pebble import CONSTS, ProcessExpired, ProcessPool

from causalplan.errors import CausalPlanError
from causalplan.service.errors import (
    InternalError,
    PlanningTimeoutError,
    QueueFullError,
    WorkerCrashedError,
    WorkerDiedError,
    error_class,
)
from causalplan.service.pool import worker
from causalplan.service.pool.turns import Turns, is_background
from causalplan.service.pool.worker import READY, STARTED, Message, is_running, remove_stale_folders

logger = logging.getLogger(__name__)

T = TypeVar("T")

START_SECONDS = 60.0
CLOSED = "closed"
"""What the pool tells its own listener when it closes."""
STOP_POLL_SECONDS = 0.02
"""How often a call with a ``stop`` event looks at it while its worker works."""
KILL_WAIT_SECONDS = CONSTS.term_timeout + 2.0
"""How long a stopped call waits for its call to reach a worker, then for pebble to kill that worker
(SIGTERM, then SIGKILL after ``term_timeout``)."""
WORK_MODULE = "causalplan.service.work.registry"
"""The functions workers run (the work layer's registry), named here so the fork server imports them once."""
_CONTEXT = multiprocessing.get_context("forkserver")
_CONTEXT.set_forkserver_preload([worker.__name__, WORK_MODULE])  # each worker forks with the planners imported


class RunStoppedError(Exception):
    """The caller's ``stop`` event was set while its worker worked: the worker was killed (and replaced)."""


@dataclass(frozen=True)
class PoolStats:
    """What /health shows of a pool; ``replaced``: workers started after the first ``workers``."""

    workers: int
    busy: int
    waiting: int
    max_in_flight: int
    completed: int
    replaced: int

    def as_dict(self) -> dict[str, int]:
        """Return the stats as a JSON-ready dict."""
        return dict(vars(self))


class PlannerPool:
    """``size`` worker processes; at most ``size + queue_size`` solves running or waiting."""

    def __init__(self, size: int, queue_size: int, memory_mb: int, queue_wait_seconds: float) -> None:
        self.size = size
        self.max_in_flight = size + queue_size
        self.memory_mb = memory_mb
        self.queue_wait_seconds = queue_wait_seconds
        self._turns = Turns(size)  # interactive requests in arrival order, background work after them
        self._lock = threading.Condition()
        self._in_flight = 0
        self._busy = 0
        self._completed = 0
        self._hellos = 0
        self._seconds_per_call = 0.05  # moving average, for Retry-After
        self._workers: set[int] = set()
        self._started: dict[int, int | None] = {}  # a run in progress -> the pid of the worker that took it
        self._futures: set[Future[Any]] = set()
        self._runs = itertools.count(1)
        self._pebble: ProcessPool | None = None
        self._messages: tuple[Connection, Connection] | None = None  # the workers' pipe: (read, write)
        self._closed = False
        self._start_lock = threading.Lock()
        self._build_lock = threading.Lock()

    def start(self) -> None:
        """Remove stale workers' folders, start the workers and wait until each has imported the planners."""
        with self._start_lock:
            self._start()

    def start_once(self) -> None:
        """Start the workers unless they are started (the jobs' pool starts with its first call)."""
        with self._start_lock:
            if self._pebble is None and not self._closed:
                self._start()

    def _start(self) -> None:
        for folder in remove_stale_folders():
            logger.info("removed %s, left by a planner worker that was killed", folder)
        self._messages = _CONTEXT.Pipe(duplex=False)
        threading.Thread(target=self._listen, args=(self._messages[0],), name="causalplan-pool", daemon=True).start()
        pebble = self._pebble_pool()
        deadline = time.monotonic() + START_SECONDS
        with self._lock:
            while self._hellos < self.size and pebble.active and time.monotonic() < deadline:
                self._lock.wait(0.1)
            ready = self._hellos >= self.size
        if not ready:
            self.close()
            raise WorkerCrashedError(
                "A planner worker did not start; run `python -c 'import causalplan.service.work.registry'` to see why."
            )

    def _new_pebble(self) -> ProcessPool:
        environment = dict(os.environ)
        writer = self._messages[1] if self._messages is not None else None
        args = (os.getpid(), environment, self.memory_mb, writer, False)
        return ProcessPool(self.size, initializer=worker.initialize, initargs=args, context=_CONTEXT)

    def _pebble_pool(self) -> ProcessPool:
        """Return the pebble pool, a new one if it is broken (a worker died while none worked)."""
        with self._build_lock:
            if self._closed:
                raise _closed()
            pebble = self._pebble
            if pebble is not None and pebble.active:
                return pebble
            if pebble is not None:
                logger.warning("a planner worker died while none worked; pebble's pool is replaced")
                _shut(pebble)
            pebble = self._new_pebble()
            pebble.active  # noqa: B018 - the property starts the workers (pebble starts them on first use)
            self._pebble = pebble
            return pebble

    def _listen(self, messages: Connection) -> None:
        """Read the workers' messages (hello, started) until the pool closes."""
        while True:
            try:
                message: Message = messages.recv()
            except (EOFError, OSError):
                messages.close()
                return
            kind, pid, run = message
            with self._lock:
                if kind == READY:
                    self._hellos += 1
                    self._workers.add(pid)
                elif kind == STARTED and run in self._started:  # not a run that has ended meanwhile
                    self._started[run] = pid
                elif kind == CLOSED:
                    messages.close()
                    return
                self._lock.notify_all()

    def worker_pids(self) -> list[int]:
        """Return the process ids of the current workers."""
        with self._lock:
            self._workers = {pid for pid in self._workers if is_running(pid)}
            return sorted(self._workers)

    def stats(self) -> PoolStats:
        """Return the pool's current numbers."""
        with self._lock:
            return PoolStats(
                self.size,
                self._busy,
                self._in_flight - self._busy,
                self.max_in_flight,
                self._completed,
                max(0, self._hellos - self.size),
            )

    def retry_after(self) -> int:
        """Return the seconds after which a refused request may find room (at least 1)."""
        with self._lock:
            return max(1, math.ceil(self._seconds_per_call * self._in_flight / self.size))

    def run(
        self,
        function: Callable[..., T],
        args: tuple[Any, ...],
        timeout: float,
        meanwhile: Callable[[], None] | None = None,
        stop: threading.Event | None = None,
    ) -> T:
        """Run ``function(*args)`` in a worker, waiting here; kill the worker after ``timeout`` seconds.

        ``stop`` (a cancelled job's): once it is set, the worker is killed, and this raises
        RunStoppedError once it is dead (a job's work may run for minutes between its own checks).

        Blocks while no worker is free (waiters are served in arrival order, background work after
        every interactive request: ``turns``): call it from a thread, not the event loop. ``meanwhile``
        runs here once a worker is ours, while it works (e.g. storing the request's record), so
        a refused request runs nothing; what it raises is raised once the worker has answered.

        Raises QueueFullError (429), PlanningTimeoutError (504), WorkerCrashedError (503; also
        once the pool is closed), the ``CausalPlanError`` the call raised, InternalError for a
        bug in the function, or what pickling the call raised.
        """
        self._admit()
        is_background_work = is_background()
        try:
            if not self._turns.take(self.queue_wait_seconds, is_background_work):
                retry = self.retry_after()
                raise QueueFullError(
                    f"No planner worker became free within {self.queue_wait_seconds:g} s. Try again in {retry} s.",
                    retry,
                )
            try:
                with self._lock:
                    self._busy += 1
                if stop is not None and stop.is_set():
                    raise RunStoppedError
                result: T = self._run_taken(function, args, timeout, meanwhile, stop)
                return result
            finally:
                with self._lock:
                    self._busy -= 1
                self._turns.give_back(is_background_work)
        finally:
            with self._lock:
                self._in_flight -= 1

    def _admit(self) -> None:
        with self._lock:
            if self._closed:
                raise _closed()
            full = self._in_flight >= self.max_in_flight
            if not full:
                self._in_flight += 1
        if full:
            retry = self.retry_after()
            raise QueueFullError(
                f"All {self.size} planner worker(s) are busy and {self.max_in_flight - self.size} request(s) "
                f"are already waiting. Try again in {retry} s.",
                retry,
            )

    def _run_taken(
        self,
        function: Callable[..., Any],
        args: tuple[Any, ...],
        timeout: float,
        meanwhile: Callable[[], None] | None,
        stop: threading.Event | None,
    ) -> Any:
        run = next(self._runs) if stop is not None else None  # only a stoppable run needs to know its worker
        if run is not None:
            with self._lock:
                self._started[run] = None
        started = time.perf_counter()
        future = self._schedule(run, function, args, timeout)
        failure: Exception | None = None
        if meanwhile is not None:
            try:
                meanwhile()
            except Exception as exc:  # noqa: BLE001 - raised once the worker has answered
                failure = exc
        try:
            try:
                reply = self._reply(future, run, timeout, stop)
            except BrokenProcessPool:  # a worker died before it took the call: its replacement does it
                future = self._schedule(run, function, args, timeout)
                reply = self._reply(future, run, timeout, stop)
        except BrokenProcessPool:
            raise WorkerCrashedError("No planner worker could take this request; try again.") from None
        finally:
            with self._lock:
                if run is not None:
                    self._started.pop(run, None)
                self._futures.discard(future)
        with self._lock:
            self._completed += 1
            self._seconds_per_call = 0.8 * self._seconds_per_call + 0.2 * (time.perf_counter() - started)
        if failure is not None:
            raise failure
        return _unwrap(reply)

    def _schedule(
        self, run: int | None, function: Callable[..., Any], args: tuple[Any, ...], timeout: float
    ) -> Future[Any]:
        pebble = self._pebble_pool()
        try:
            future: Future[Any] = pebble.schedule(worker.run_call, (run, function, args), timeout=timeout)
        except RuntimeError:  # broken since we looked
            future = self._pebble_pool().schedule(worker.run_call, (run, function, args), timeout=timeout)
        with self._lock:
            self._futures.add(future)
        return future

    def _reply(
        self, future: Future[Any], run: int | None, timeout: float, stop: threading.Event | None
    ) -> tuple[Any, ...]:
        """Return the worker's reply to ``run``; kill its worker when ``stop`` is set (RunStoppedError)."""
        while run is not None and stop is not None and not wait([future], STOP_POLL_SECONDS).done:
            if stop.is_set():
                self._kill(future, run)
                raise RunStoppedError
        try:
            reply: tuple[Any, ...] = future.result()
            return reply
        except TimeoutError:
            remove_stale_folders()  # a worker killed outright (SIGKILL) could not remove its own
            raise PlanningTimeoutError(
                f"The planner worker was still busy {timeout:g} s after the solve started, so it was "
                "stopped. Try a smaller model or a lower time_limit.",
                details={"seconds": round(timeout, 3)},
            ) from None
        except ProcessExpired as exc:
            remove_stale_folders()
            raise WorkerDiedError(
                "The planner worker running this request stopped unexpectedly (killed, out of memory, "
                "or crashed). It has been replaced; sending the request again should work.",
                details={"exit_code": exc.exitcode},
            ) from None
        except CancelledError:  # by ``close``
            raise WorkerCrashedError(
                "The planner pool closed while this request ran (the server is stopping). Try again."
            ) from None

    def _kill(self, future: Future[Any], run: int) -> None:
        """Cancel ``future`` once a worker has it (pebble then kills that worker); wait until the worker is dead.

        A call on its way to a worker is let arrive first: cancelled on the way, it would still
        be run by the worker that takes it, until pebble kills that one too.
        """
        deadline = time.monotonic() + KILL_WAIT_SECONDS
        with self._lock:
            while self._started.get(run) is None and not future.done() and time.monotonic() < deadline:
                self._lock.wait(STOP_POLL_SECONDS)
            pid = self._started.get(run)
        if not future.cancel():  # it has just ended: no worker to kill
            return
        deadline = time.monotonic() + KILL_WAIT_SECONDS
        while pid is not None and is_running(pid) and time.monotonic() < deadline:
            time.sleep(0.01)
        remove_stale_folders()

    def run_isolated(self, function: Callable[..., T], args: tuple[Any, ...], timeout: float) -> T:
        """Run one call in a fresh worker process that exits afterwards (for probes that import a lot)."""
        initargs = (os.getpid(), dict(os.environ), self.memory_mb, None, True)
        pebble = ProcessPool(1, initializer=worker.initialize, initargs=initargs, context=_CONTEXT)
        try:
            reply = pebble.schedule(worker.run_call, (None, function, args), timeout=timeout).result()
        except TimeoutError:
            raise PlanningTimeoutError(f"The probe did not finish within {timeout:g} s.") from None
        except (ProcessExpired, BrokenProcessPool):
            raise WorkerCrashedError("The probe process stopped unexpectedly.") from None
        finally:
            _shut(pebble)
        result: T = _unwrap(reply)
        return result

    def close(self) -> None:
        """Stop every worker (busy ones are killed; their requests get 503)."""
        with self._build_lock, self._lock:
            self._closed = True
            pebble, self._pebble = self._pebble, None
            futures = list(self._futures)
        for future in futures:
            future.cancel()
        if pebble is not None:
            _shut(pebble)
        with self._lock:
            pipe, self._messages = self._messages, None
        if pipe is not None:
            pipe[1].send((CLOSED, 0, 0))
            pipe[1].close()
        remove_stale_folders()


def _shut(pebble: ProcessPool) -> None:
    """Stop ``pebble``'s workers (SIGTERM, then SIGKILL after ``term_timeout``) and wait for them."""
    pebble.stop()  # type: ignore[no-untyped-call]  # pebble's stop() has no annotations
    pebble.join()


def _closed() -> WorkerCrashedError:
    return WorkerCrashedError("The planner pool is closed: the server is stopping. Try again.")


def _unwrap(reply: tuple[Any, ...]) -> Any:
    kind = reply[0]
    if kind == "ok":
        return reply[1]
    if kind == "error":
        _, code, message, details = reply
        try:
            error = error_class(code)(message, details=details)
        except TypeError:  # a class with another constructor: keep the code, lose the class
            error = CausalPlanError(message, details=details)
        # A class this process has not imported (e.g. the consensus's) is found as the root: keep the code.
        error.code = code
        raise error
    logger.error("planner worker call failed:\n%s", reply[1])
    raise InternalError("The planner failed unexpectedly; the server log has the details.")
