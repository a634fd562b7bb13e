"""The planner pool: worker processes that each run one solve at a time, behind a queue limit.

Why not ``concurrent.futures.ProcessPoolExecutor``: when one of its workers dies, the whole
executor breaks and every queued solve fails; and it cannot kill the one worker that overruns
its time limit. Here each request owns one worker while it runs, so a killed or stuck worker
fails only that request, and is replaced before the next one needs it.

Request threads call ``PlannerPool.run``, which blocks the calling thread, never the event loop.
Or they call ``PlannerPool.submit``, which blocks only until a worker has the job, and the event
loop awaits the answer (``SentJob.reply``): the worker's answer then wakes the loop itself, not
a thread that would then hand it over. Measured on cold POST /v1/plans, two servers interleaved
six times each (300 new models per run): p50 8.00 -> 6.89 ms (median of the runs' p50s).
"""

from __future__ import annotations

import asyncio
import logging
import math
import os
import queue
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from contextlib import suppress
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any, Generic, TypeVar

import anyio

from causalplan.errors import CausalPlanError
from causalplan.service.errors import (
    InternalError,
    PlanningTimeoutError,
    QueueFullError,
    WorkerCrashedError,
    error_class,
)

logger = logging.getLogger(__name__)

T = TypeVar("T")

_STOP_SECONDS = 2.0
_START_SECONDS = 60.0
_WORKER_MAIN = "from causalplan.service.worker import main; main()"


def _worker_environment(temp_folder: Path) -> dict[str, str]:
    # Jobs are pickled by reference (module and name), so a worker must import what the app
    # can: it gets the app's import path, not just the interpreter's default one.
    # TMPDIR: ``tempfile`` (and FD's processes, which inherit it) put their folders under the
    # worker's own temp folder, which the app removes however the worker ends (see ``_Worker``).
    return {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(path for path in sys.path if path),
        "TMPDIR": str(temp_folder),
    }


def _children_of(pid: int) -> list[int]:
    """Return the pids of the children of process ``pid`` (empty when /proc does not list them)."""
    children: list[int] = []
    with suppress(OSError):
        for task in Path(f"/proc/{pid}/task").iterdir():
            with suppress(OSError, ValueError):
                children.extend(int(child) for child in (task / "children").read_text().split())
    return children


class _Worker:
    """One worker process (``python -c 'from causalplan.service.worker import main; main()'``).

    It is a fresh interpreter, not a fork of the app (which runs uvicorn's and anyio's threads),
    in a process group of its own, and talks to the app over a private socket pair.

    It also gets a temp folder of its own (its TMPDIR), made and removed here, by the app:
    a worker removes its search processes' folders when it exits cleanly, but one that is
    killed (a timeout, a crash) cannot, and they would stay in the system temp folder forever.
    ``kill`` and ``stop``, which every way of ending a worker goes through, remove it.
    """

    def __init__(self, memory_mb: int, quiet: bool = False) -> None:
        self.temp_folder = Path(tempfile.mkdtemp(prefix="causalplan-worker-"))
        self._temp_folder_lock = threading.Lock()
        self._temp_folder_removed = False
        parent_end, child_end = socket.socketpair()
        try:
            with child_end:
                self.process = subprocess.Popen(
                    [sys.executable, "-c", _WORKER_MAIN, str(child_end.fileno()), str(memory_mb)],
                    pass_fds=[child_end.fileno()],
                    stdin=subprocess.DEVNULL,
                    stdout=subprocess.DEVNULL,  # C extensions print banners; errors still reach stderr
                    stderr=subprocess.DEVNULL if quiet else None,
                    process_group=0,
                    env=_worker_environment(self.temp_folder),
                )
        except BaseException:  # no worker, so no ``kill`` or ``stop`` will come to clean up
            parent_end.close()
            self._remove_temp_folder()
            raise
        self.connection = Connection(parent_end.detach())
        self.is_ready = False

    @property
    def pid(self) -> int:
        return self.process.pid

    def is_alive(self) -> bool:
        return self.process.poll() is None

    def wait_ready(self, timeout: float) -> None:
        """Wait for the worker's hello (sent once it has imported the planners)."""
        if self.is_ready:
            return
        if not self.connection.poll(timeout):
            raise TimeoutError
        self.connection.recv()
        self.is_ready = True

    def call(
        self,
        function: Callable[..., Any],
        args: tuple[Any, ...],
        timeout: float,
        meanwhile: Callable[[], None] | None = None,
    ) -> tuple[Any, ...]:
        """Send one job and return the worker's reply; TimeoutError or EOFError when there is none.

        A worker that has just been started is waited for first, within the same ``timeout``.
        ``meanwhile`` (which must not raise) runs in this thread once the job is sent, while the
        worker works on it.
        """
        deadline = time.monotonic() + timeout
        self.wait_ready(timeout)
        self.connection.send((function, args))
        if meanwhile is not None:
            meanwhile()
        if not self.connection.poll(max(0.0, deadline - time.monotonic())):
            raise TimeoutError
        reply: tuple[Any, ...] = self.connection.recv()  # EOFError when the worker died
        return reply

    def exit_code(self) -> int | None:
        """Return the exit code of a worker that has stopped (None if it is still running)."""
        try:
            return self.process.wait(_STOP_SECONDS)
        except subprocess.TimeoutExpired:
            return None

    def kill(self) -> None:
        """Kill the worker and what it started in its process group (the translator); remove its temp folder.

        Safe to call more than once, and from two threads at once (a closing pool and the
        request that timed out may both kill a busy worker).
        """
        try:
            # Its search processes run in sessions of their own (so a timed-out search can be
            # killed without its worker): found before the worker dies, killed with it.
            children = _children_of(self.process.pid)
            with suppress(ProcessLookupError, PermissionError):
                os.killpg(self.process.pid, signal.SIGKILL)
            for child in children:
                with suppress(ProcessLookupError, PermissionError):
                    os.killpg(child, signal.SIGKILL)
            with suppress(ProcessLookupError):
                self.process.kill()
            self.process.wait()
            self.connection.close()
        finally:
            self._remove_temp_folder()

    def stop(self) -> None:
        """Ask the worker to finish, and kill it if it does not; remove its temp folder."""
        with suppress(BrokenPipeError, OSError):
            self.connection.send(None)
        try:
            self.process.wait(_STOP_SECONDS)
        except subprocess.TimeoutExpired:
            self.kill()
        else:
            try:
                self.connection.close()
            finally:
                self._remove_temp_folder()

    def _remove_temp_folder(self) -> None:
        """Remove the worker's temp folder and all in it, once; never raise.

        A killed worker's search processes are killed with it (``kill``), so none writes here afterwards.
        """
        with self._temp_folder_lock:
            if self._temp_folder_removed:
                return
            self._temp_folder_removed = True
        shutil.rmtree(self.temp_folder, ignore_errors=True)


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
        # Last in, first out: the worker that finished last (its caches and its started search
        # process still warm) takes the next job; the others wait for a busier moment.
        self._idle: queue.LifoQueue[_Worker] = queue.LifoQueue()
        self._lock = threading.Lock()
        self._in_flight = 0
        self._busy = 0
        self._completed = 0
        self._replaced = 0
        self._seconds_per_job = 0.05  # moving average, for Retry-After
        self._workers: set[_Worker] = set()
        self._closed = False

    def start(self) -> None:
        """Start the workers and wait until each has imported the planners."""
        workers = [self._spawn() for _ in range(self.size)]
        try:
            for worker in workers:
                worker.wait_ready(_START_SECONDS)
        except (TimeoutError, EOFError, OSError):
            self.close()
            raise WorkerCrashedError(
                "A planner worker did not start; run `python -c 'import causalplan.service.worker'` to see why."
            ) from None
        for worker in workers:
            self._idle.put(worker)

    def _spawn(self) -> _Worker:
        worker = _Worker(self.memory_mb)
        with self._lock:
            self._workers.add(worker)
        return worker

    def _discard(self, worker: _Worker) -> None:
        with self._lock:
            self._workers.discard(worker)
            self._replaced += 1

    def worker_pids(self) -> list[int]:
        """Return the process ids of the current workers."""
        with self._lock:
            return [worker.pid for worker in self._workers]

    def stats(self) -> PoolStats:
        """Return the pool's current numbers."""
        with self._lock:
            return PoolStats(
                self.size,
                self._busy,
                self._in_flight - self._busy,
                self.max_in_flight,
                self._completed,
                self._replaced,
            )

    def retry_after(self) -> int:
        """Return the seconds after which a refused request may find room (at least 1)."""
        with self._lock:
            return max(1, math.ceil(self._seconds_per_job * self._in_flight / self.size))

    def _admit(self) -> None:
        """Count one more solve running or waiting; QueueFullError (429) when there is no room."""
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

    def _take_worker(self) -> _Worker:
        try:
            worker = self._idle.get(timeout=self.queue_wait_seconds)
        except queue.Empty:
            retry = self.retry_after()
            raise QueueFullError(
                f"No planner worker became free within {self.queue_wait_seconds:g} s. Try again in {retry} s.", retry
            ) from None
        if not worker.is_alive():  # died while idle (e.g. killed from outside): not this request's fault
            logger.warning("planner worker %s died while idle; replacing it", worker.pid)
            self._discard(worker)
            worker.kill()
            worker = self._spawn()
        return worker

    def run(
        self,
        function: Callable[..., T],
        args: tuple[Any, ...],
        timeout: float,
        meanwhile: Callable[[], None] | None = None,
    ) -> T:
        """Run ``function(*args)`` in a worker and wait for its answer here; kill it after ``timeout`` seconds.

        ``submit`` and then ``SentJob.wait``: see there for ``meanwhile`` and what is raised.
        """
        job: SentJob[T] = self.submit(function, args, timeout, meanwhile)
        return job.wait()

    def submit(
        self,
        function: Callable[..., T],
        args: tuple[Any, ...],
        timeout: float,
        meanwhile: Callable[[], None] | None = None,
    ) -> SentJob[T]:
        """Send ``function(*args)`` to a free worker (waiting for one if need be); return the job to wait for.

        Blocks while no worker is free, and while a just-started worker imports: call it from a
        thread, not the event loop. The answer is waited for by ``SentJob.wait`` in a thread, or
        by ``SentJob.reply`` on the event loop (no thread hop back); the worker is killed if it
        has not answered ``timeout`` seconds after the job was sent.

        ``meanwhile`` runs in the calling thread once the job is sent, while the worker works on
        it (e.g. storing the request's record): only once a worker has the job, so a refused
        request (429) runs nothing. What it raises is raised once the worker has answered, in
        place of the job's own answer or error (a worker that timed out or crashed is reported as
        such instead).

        Raises QueueFullError (429). The rest comes from the ``SentJob``: PlanningTimeoutError
        (504), WorkerCrashedError (503), what sending the job raised (e.g. it cannot be pickled),
        the ``CausalPlanError`` the job raised, or InternalError for a bug in the job.
        """
        self._admit()
        try:
            worker = self._take_worker()
        except BaseException:
            with self._lock:
                self._in_flight -= 1
            raise
        with self._lock:
            self._busy += 1
        job: SentJob[T] = SentJob(self, worker, timeout)
        try:
            worker.wait_ready(timeout)
            worker.connection.send((function, args))
        except BaseException as exc:  # noqa: BLE001 - e.g. a job that cannot be pickled: raised by the SentJob
            job.unsent = exc
            return job
        if meanwhile is not None:
            try:
                meanwhile()
            except Exception as exc:  # noqa: BLE001 - raised once the worker has answered
                job.failure = exc
        return job

    def _end(self, worker: _Worker | None, seconds: float | None = None) -> None:
        """A sent job is over: count it out, and give its worker back (None: replaced instead).

        ``seconds``: how long the job took, for a job that was answered.
        """
        with self._lock:
            self._in_flight -= 1
            self._busy -= 1
            if seconds is not None:
                self._completed += 1
                self._seconds_per_job = 0.8 * self._seconds_per_job + 0.2 * seconds
        if worker is not None:
            self._idle.put(worker)

    def _replace(self, worker: _Worker) -> None:
        logger.warning("replacing planner worker %s", worker.pid)
        worker.kill()
        self._discard(worker)
        if not self._closed:
            self._idle.put(self._spawn())

    def run_isolated(self, function: Callable[..., T], args: tuple[Any, ...], timeout: float) -> T:
        """Run one job in a fresh process that exits afterwards (for probes that import a lot)."""
        worker = _Worker(self.memory_mb, quiet=True)
        try:
            reply = worker.call(function, args, timeout)
        except TimeoutError:
            worker.kill()
            raise PlanningTimeoutError(f"The probe did not finish within {timeout:g} s.") from None
        except (EOFError, OSError):
            worker.kill()
            raise WorkerCrashedError("The probe process stopped unexpectedly.") from None
        except BaseException:  # e.g. a job that cannot be pickled: the process and its folder go too
            worker.kill()
            raise
        worker.stop()
        result: T = _unwrap(reply)
        return result

    def close(self) -> None:
        """Stop every worker (busy ones are killed)."""
        self._closed = True
        with self._lock:
            workers = list(self._workers)
            self._workers.clear()
        idle: set[_Worker] = set()
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


class SentJob(Generic[T]):
    """A job sent to a worker (``PlannerPool.submit``): its answer, waited for once.

    ``wait`` waits in the calling thread; ``reply`` on the event loop, which the worker's
    answer then wakes directly: no thread to wake and hop back from.
    """

    def __init__(self, pool: PlannerPool, worker: _Worker, timeout: float) -> None:
        self._pool = pool
        self._worker = worker
        self._timeout = timeout
        self._started = time.perf_counter()
        self._deadline = time.monotonic() + timeout
        self._finished = False
        self.unsent: BaseException | None = None
        """What sending the job raised (the worker then never had it)."""
        self.failure: Exception | None = None
        """What ``meanwhile`` raised: raised once the worker has answered."""

    def _remaining(self) -> float:
        return max(0.0, self._deadline - time.monotonic())

    def wait(self) -> T:
        """Wait here for the worker's answer; return it or raise (see ``PlannerPool.submit``)."""
        try:
            ready = self.unsent is None and self._worker.connection.poll(self._remaining())
        except OSError:  # its connection is closed (the pool is closing): reading it says so
            ready = True
        return self._conclude(self._receive(ready))

    async def reply(self) -> T:
        """Wait on the event loop for the worker's answer; return it or raise, as ``wait`` does.

        A worker that gave no answer (it timed out or died) is replaced in a thread: that
        starts a process. If this wait is cancelled, the answer would never be read, so the
        worker is replaced then too (the next job must not get this one's answer).
        """
        ready = True
        if self.unsent is None:
            try:
                if not self._worker.connection.poll(0):
                    ready = await _readable(self._worker.connection, self._remaining())
            except OSError:  # its connection is closed (the pool is closing): reading it says so
                ready = True
            except BaseException:
                self.abandon()
                raise
        outcome = self._receive(ready)
        if isinstance(outcome, BaseException):
            result: T = await anyio.to_thread.run_sync(self._conclude, outcome)
            return result
        return self._conclude(outcome)

    def _receive(self, ready: bool) -> tuple[Any, ...] | BaseException:
        """Return the worker's reply (``ready``: it is there, or the worker's end), or what went wrong instead."""
        self._finish()
        try:
            if self.unsent is not None:
                return self.unsent
            if not ready:
                return TimeoutError()
            reply: tuple[Any, ...] = self._worker.connection.recv()  # EOFError when the worker died
        except BaseException as exc:  # noqa: BLE001 - dealt with by _conclude
            return exc
        return reply

    def _conclude(self, outcome: tuple[Any, ...] | BaseException) -> T:
        """Give the worker back and return its answer; or replace it, and raise what went wrong."""
        pool, worker = self._pool, self._worker
        if not isinstance(outcome, BaseException):
            pool._end(worker, time.perf_counter() - self._started)
            if self.failure is not None:
                raise self.failure
            result: T = _unwrap(outcome)
            return result
        timed_out = isinstance(outcome, TimeoutError)  # an OSError too: asked first
        crashed = not timed_out and isinstance(outcome, EOFError | OSError)
        exit_code = worker.exit_code() if crashed else None
        pool._replace(worker)
        pool._end(None)
        if timed_out:
            raise PlanningTimeoutError(
                f"The planner worker was still busy {self._timeout:g} s after the solve started, so it was "
                "stopped. Try a smaller model or a lower time_limit.",
                details={"seconds": round(self._timeout, 3)},
            )
        if crashed:
            raise WorkerCrashedError(
                "The planner worker running this request stopped unexpectedly (killed, out of memory, "
                "or crashed). It has been replaced; sending the request again should work.",
                details={"exit_code": exit_code},
            )
        raise outcome  # e.g. a job that could not be pickled: its worker's state was unknown

    def _finish(self) -> None:
        assert not self._finished, "a job's answer is read once"
        self._finished = True

    def abandon(self) -> None:
        """Give up the answer unread (a cancelled wait): the worker is replaced, so the next job does not get it."""
        if not self._finished:
            self._finish()
            self._pool._replace(self._worker)
            self._pool._end(None)


def _settle(future: asyncio.Future[bool], value: bool) -> None:
    if not future.done():
        future.set_result(value)


async def _readable(connection: Connection, seconds: float) -> bool:
    """Wait on the event loop until ``connection`` can be read (an answer, or its end); False after ``seconds``.

    The loop watches a descriptor of its own for the socket: a connection closed meanwhile by
    another thread (a closing pool kills the worker, then closes it) would otherwise leave the
    loop nothing to wake it before ``seconds``.
    """
    loop = asyncio.get_running_loop()
    readable: asyncio.Future[bool] = loop.create_future()
    descriptor = os.dup(connection.fileno())
    try:
        loop.add_reader(descriptor, _settle, readable, True)
        timer = loop.call_later(seconds, _settle, readable, False)
        try:
            return await readable
        finally:
            timer.cancel()
            loop.remove_reader(descriptor)
    finally:
        os.close(descriptor)


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
            error.code = code
        raise error
    logger.error("planner worker job failed:\n%s", reply[1])
    raise InternalError("The planner failed unexpectedly; the server log has the details.")
