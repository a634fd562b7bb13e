"""The planner pool: worker processes that each run one solve at a time, behind a queue limit.

Why not ``concurrent.futures.ProcessPoolExecutor``: when one of its workers dies, the whole
executor breaks and every queued solve fails; and it cannot kill the one worker that overruns
its time limit. Here each solve owns one worker while it runs, so a killed, stuck or crashed
worker fails only that solve, and is replaced before the next one needs it.

``PlannerPool.run`` blocks the calling thread (a route's worker thread, never the event loop).
A worker says "started" as soon as it has a job: a worker that dies before that never began
the job, which then goes to its replacement. That closes the race behind the flake in which a
worker killed while idle was still exiting (no zombie yet, so ``poll`` said it ran, and its
socket still open, so the job could be sent) when a request took it, and the request got 503.
"""

from __future__ import annotations

import logging
import math
import pickle
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

from causalplan.errors import CausalPlanError
from causalplan.service.errors import (
    InternalError,
    PlanningTimeoutError,
    QueueFullError,
    WorkerCrashedError,
    error_class,
)
from causalplan.service.pool.process import WorkerProcess, remove_stale_folders

logger = logging.getLogger(__name__)

T = TypeVar("T")

START_SECONDS = 60.0
STARTED = "started"
"""What a worker sends first when it receives a job."""
STOP_POLL_SECONDS = 0.02
"""How often a call with a ``stop`` event looks at it while its worker works."""


class _NotTaken(Exception):
    """The worker ended before it said it had the job (so it never ran it)."""


class RunStoppedError(Exception):
    """The caller's ``stop`` event was set while its worker worked: the worker was killed (and replaced)."""


@dataclass(frozen=True)
class PoolStats:
    """What /health shows of the pool."""

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
        # Last in, first out: the worker that finished last (its caches warm) takes the next job.
        self._idle: queue.LifoQueue[WorkerProcess] = queue.LifoQueue()
        self._lock = threading.Lock()
        self._in_flight = 0
        self._busy = 0
        self._completed = 0
        self._replaced = 0
        self._seconds_per_job = 0.05  # moving average, for Retry-After
        self._workers: set[WorkerProcess] = set()
        self._closed = False
        self._start_lock = threading.Lock()
        self._started = False

    def start(self) -> None:
        """Remove stale workers' folders, start the workers and wait until each has imported the planners."""
        with self._start_lock:
            self._start()

    def start_once(self) -> None:
        """Start the workers unless they are started (the jobs' pool starts when its first job comes)."""
        with self._start_lock:
            if not self._started and not self._closed:
                self._start()

    def _start(self) -> None:
        self._started = True
        for folder in remove_stale_folders():
            logger.info("removed %s, left by a planner worker of a server that was killed", folder)
        workers = [self._spawn() for _ in range(self.size)]
        try:
            for worker in workers:
                worker.wait_ready(START_SECONDS)
        except (TimeoutError, EOFError, OSError):
            self.close()
            raise WorkerCrashedError(
                "A planner worker did not start; run `python -c 'import causalplan.service.pool.jobs'` to see why."
            ) from None
        for worker in workers:
            self._idle.put(worker)

    def _spawn(self) -> WorkerProcess:
        worker = WorkerProcess(self.memory_mb)
        with self._lock:
            self._workers.add(worker)
        return worker

    def worker_pids(self) -> list[int]:
        """Return the process ids of the current workers."""
        with self._lock:
            return [worker.pid for worker in self._workers]

    def stats(self) -> PoolStats:
        """Return the pool's current numbers."""
        with self._lock:
            return PoolStats(
                self.size, self._busy, self._in_flight - self._busy, self.max_in_flight, self._completed, self._replaced
            )

    def retry_after(self) -> int:
        """Return the seconds after which a refused request may find room (at least 1)."""
        with self._lock:
            return max(1, math.ceil(self._seconds_per_job * self._in_flight / self.size))

    def run(
        self,
        function: Callable[..., T],
        args: tuple[Any, ...],
        timeout: float,
        meanwhile: Callable[[], None] | None = None,
        stop: threading.Event | None = None,
    ) -> T:
        """Run ``function(*args)`` in a worker, waiting here; kill the worker after ``timeout`` seconds.

        ``stop`` (a cancelled job's): once it is set, the worker is killed at once, and this
        raises RunStoppedError (a job's work may run for minutes between its own checks).

        Blocks while no worker is free: call it from a thread, not the event loop. ``meanwhile``
        runs here once a worker has the job, while it works (e.g. storing the request's record),
        so a refused request runs nothing; what it raises is raised once the worker has answered.

        Raises QueueFullError (429), PlanningTimeoutError (504), WorkerCrashedError (503), the
        ``CausalPlanError`` the job raised, InternalError for a bug in the job, or what pickling
        the job raised.
        """
        job = pickle.dumps((function, args), protocol=pickle.HIGHEST_PROTOCOL)  # before any worker is taken
        self._admit()
        try:
            if stop is not None and stop.is_set():
                raise RunStoppedError
            result: T = self._run_admitted(job, timeout, meanwhile, stop)
            return result
        finally:
            with self._lock:
                self._in_flight -= 1

    def _admit(self) -> None:
        with self._lock:
            full = self._closed or self._in_flight >= self.max_in_flight
            if not full:
                self._in_flight += 1
        if full:
            retry = self.retry_after()
            raise QueueFullError(
                f"All {self.size} planner worker(s) are busy and {self.max_in_flight - self.size} request(s) "
                f"are already waiting. Try again in {retry} s.",
                retry,
            )

    def _take_worker(self) -> WorkerProcess:
        try:
            worker = self._idle.get(timeout=self.queue_wait_seconds)
        except queue.Empty:
            retry = self.retry_after()
            raise QueueFullError(
                f"No planner worker became free within {self.queue_wait_seconds:g} s. Try again in {retry} s.", retry
            ) from None
        if not worker.is_alive():  # died while idle (e.g. killed from outside): not this request's fault
            logger.warning("planner worker %s died while idle; replacing it", worker.pid)
            self._replace(worker)
            return self._take_worker()
        return worker

    def _run_admitted(
        self, job: bytes, timeout: float, meanwhile: Callable[[], None] | None, stop: threading.Event | None
    ) -> Any:
        for _ in range(2):  # a worker that ends before it takes the job hands it to its replacement
            worker = self._take_worker()
            with self._lock:
                self._busy += 1
            started = time.perf_counter()
            try:
                reply = self._call(worker, job, timeout, meanwhile, stop)
            except RunStoppedError:
                self._give_back(worker, None, replace=True)
                raise
            except _NotTaken:
                logger.warning("planner worker %s ended before taking its job; replacing it", worker.pid)
                self._give_back(worker, None, replace=True)
                if self._closed:  # closing: no replacement will come
                    break
                continue
            except TimeoutError:
                self._give_back(worker, None, replace=True)
                raise PlanningTimeoutError(
                    f"The planner worker was still busy {timeout:g} s after the solve started, so it was "
                    "stopped. Try a smaller model or a lower time_limit.",
                    details={"seconds": round(timeout, 3)},
                ) from None
            except (EOFError, OSError):
                exit_code = worker.exit_code()
                self._give_back(worker, None, replace=True)
                raise WorkerCrashedError(
                    "The planner worker running this request stopped unexpectedly (killed, out of memory, "
                    "or crashed). It has been replaced; sending the request again should work.",
                    details={"exit_code": exit_code},
                ) from None
            self._give_back(worker, time.perf_counter() - started)
            result, failure = reply
            if failure is not None:
                raise failure
            return _unwrap(result)
        raise WorkerCrashedError("No planner worker could take this request (they ended or are closing); try again.")

    @staticmethod
    def _call(
        worker: WorkerProcess,
        job: bytes,
        timeout: float,
        meanwhile: Callable[[], None] | None,
        stop: threading.Event | None = None,
    ) -> tuple[tuple[Any, ...], Exception | None]:
        """Send ``job`` to ``worker``; return its reply and what ``meanwhile`` raised (RunStoppedError on ``stop``)."""
        deadline = time.monotonic() + timeout
        try:
            worker.wait_ready(timeout)
            worker.connection.send_bytes(job)
            if worker.receive(deadline - time.monotonic()) != STARTED:
                raise EOFError("the worker's first answer was not that it started")
        except TimeoutError:  # an OSError, but not an ended worker
            raise
        except (EOFError, OSError):
            raise _NotTaken from None
        failure: Exception | None = None
        if meanwhile is not None:
            try:
                meanwhile()
            except Exception as exc:  # noqa: BLE001 - raised once the worker has answered
                failure = exc
        while stop is not None and not worker.connection.poll(
            max(0.0, min(STOP_POLL_SECONDS, deadline - time.monotonic()))
        ):
            if stop.is_set():
                raise RunStoppedError
            if time.monotonic() >= deadline:
                raise TimeoutError
        reply: tuple[Any, ...] = worker.receive(deadline - time.monotonic())
        return reply, failure

    def _give_back(self, worker: WorkerProcess, seconds: float | None, replace: bool = False) -> None:
        """A job is over: count it, and put its worker back idle (or a new one in its place)."""
        with self._lock:
            self._busy -= 1
            if seconds is not None:
                self._completed += 1
                self._seconds_per_job = 0.8 * self._seconds_per_job + 0.2 * seconds
        if replace:
            self._replace(worker)
        else:
            self._idle.put(worker)

    def _replace(self, worker: WorkerProcess) -> None:
        logger.warning("replacing planner worker %s", worker.pid)
        worker.kill()
        with self._lock:
            self._workers.discard(worker)
            self._replaced += 1
        if not self._closed:
            self._idle.put(self._spawn())

    def run_isolated(self, function: Callable[..., T], args: tuple[Any, ...], timeout: float) -> T:
        """Run one job in a fresh process that exits afterwards (for probes that import a lot)."""
        worker = WorkerProcess(self.memory_mb, quiet=True)
        try:
            reply, _ = self._call(worker, pickle.dumps((function, args)), timeout, None)
        except TimeoutError:
            worker.kill()
            raise PlanningTimeoutError(f"The probe did not finish within {timeout:g} s.") from None
        except (_NotTaken, EOFError, OSError):
            worker.kill()
            raise WorkerCrashedError("The probe process stopped unexpectedly.") from None
        worker.stop()
        result: T = _unwrap(reply)
        return result

    def close(self) -> None:
        """Stop every worker (busy ones are killed; their requests get 503)."""
        self._closed = True
        with self._lock:
            workers = list(self._workers)
            self._workers.clear()
        idle: set[WorkerProcess] = set()
        while True:
            try:
                idle.add(self._idle.get_nowait())
            except queue.Empty:
                break
        for worker in workers:
            if worker in idle:
                worker.stop()
            else:
                worker.kill()


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
    logger.error("planner worker job failed:\n%s", reply[1])
    raise InternalError("The planner failed unexpectedly; the server log has the details.")
