"""The job runner of one replica: threads that claim jobs from the database, do them, and store the results.

Each thread takes one job at a time (``store.claim_job``), renews the job's lease every third
of ``job_lease_seconds`` while the work goes on, and stores the result with a write that only
the lease's owner can make. A cancel stops the work at once: ``cancel`` (what DELETE calls in
this replica) sets the job's stop event, which kills its worker; a job cancelled through
another replica is seen within ``job_poll_seconds`` (its row is no longer this runner's).

A replica that dies mid-job stops renewing; once the lease has lapsed, another replica's
runner takes the job up again. A replica that stops cleanly puts its running jobs back in the
queue at once.
"""

from __future__ import annotations

import logging
import os
import socket
import threading
import time
import uuid
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from causalplan.errors import CausalPlanError
from causalplan.service.errors import InternalError
from causalplan.service.jobs.kinds import KINDS
from causalplan.service.jobs.work import JobCancelledError, Outcome, Progress
from causalplan.service.storage import jobs as store
from causalplan.service.storage.jobs import JobKind
from causalplan.service.storage.records import JobRecord

if TYPE_CHECKING:
    from causalplan.service.deps import Services

logger = logging.getLogger(__name__)

SWEEP_SECONDS = 60.0
"""How often a runner deletes expired jobs."""


def replica_name() -> str:
    """Return a name for this server process, unique among replicas: host, process id, and a random part."""
    return f"{socket.gethostname()[:64]}:{os.getpid()}:{uuid.uuid4().hex[:8]}"


def error_of(exc: CausalPlanError) -> dict[str, Any]:
    """Return an error in the one shape's inner part: code, message, details."""
    return {"code": exc.code, "message": exc.message, "details": exc.details}


@dataclass
class _Running:
    """A job this runner does: ``stop`` ends its work, ``ended`` is set once its worker is free."""

    stop: threading.Event = field(default_factory=threading.Event)
    ended: threading.Event = field(default_factory=threading.Event)


class JobRunner:
    """``settings.job_runners`` threads doing jobs for the replica that owns ``services``."""

    def __init__(self, services: Services) -> None:
        self.services = services
        self.owner = replica_name()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._last_sweep = 0.0
        self._lock = threading.Lock()
        self._busy = 0
        self._running: dict[uuid.UUID, _Running] = {}

    def stats(self) -> dict[str, int]:
        """Return this replica's runner threads: how many, and how many are doing a job now."""
        with self._lock:
            return {"threads": len(self._threads), "busy": self._busy}

    def cancel(self, job_id: uuid.UUID, seconds: float) -> bool:
        """Stop the work of job ``job_id`` if this runner does it (cancelled in the database already).

        Waits up to ``seconds`` for its worker to be killed; return whether the work ended here.
        """
        with self._lock:
            running = self._running.get(job_id)
        if running is None:
            return False
        running.stop.set()
        return running.ended.wait(seconds)

    def start(self) -> None:
        """Start the runner threads (none when ``job_runners`` is 0)."""
        for number in range(self.services.settings.job_runners):
            thread = threading.Thread(target=self._loop, name=f"causalplan-jobs-{number}", daemon=True)
            thread.start()
            self._threads.append(thread)

    def stop(self, seconds: float = 2.0) -> None:
        """Ask the threads to stop; wait up to ``seconds`` for them (a job in a worker ends when the pool closes)."""
        self._stop.set()
        self.join(seconds)

    def join(self, seconds: float) -> None:
        """Wait up to ``seconds`` in all for the threads to end."""
        deadline = time.monotonic() + seconds
        for thread in self._threads:
            thread.join(max(0.0, deadline - time.monotonic()))

    def _loop(self) -> None:
        settings = self.services.settings
        while not self._stop.is_set():
            try:
                self._sweep()
                job = store.claim_job(
                    self.services.engine,
                    self.owner,
                    settings.job_lease_seconds,
                    list(KINDS),
                    settings.job_result_seconds,
                )
            except CausalPlanError as exc:  # the database is down: say so, try again later
                logger.warning("the job runner cannot use the database: %s", exc.message)
                job = None
            if job is None:
                self._stop.wait(settings.job_poll_seconds)
                continue
            with self._lock:
                self._busy += 1
            try:
                self._run(job)
            except CausalPlanError as exc:  # the result could not be stored: the lease lapses, the job is redone
                logger.warning("job %s could not be stored: %s", job.id, exc.message)
            finally:
                with self._lock:
                    self._busy -= 1

    def _sweep(self) -> None:
        if time.monotonic() - self._last_sweep >= SWEEP_SECONDS:
            self._last_sweep = time.monotonic()
            store.delete_expired(self.services.engine)

    def _run(self, job: JobRecord) -> None:
        engine, settings = self.services.engine, self.services.settings
        lease, keep = settings.job_lease_seconds, settings.job_result_seconds
        running = _Running()
        lost = threading.Event()
        finished = threading.Event()
        state = {"progress": (job.done, job.total)}

        def lose() -> None:
            lost.set()
            running.stop.set()

        def heartbeat() -> None:
            # Looks often (is the job still ours? else it was cancelled), renews every third of the lease.
            renewed = time.monotonic()
            while not finished.wait(min(lease / 3, settings.job_poll_seconds)):
                try:
                    if time.monotonic() - renewed >= lease / 3:
                        renewed = time.monotonic()
                        held = store.renew_lease(engine, job.id, self.owner, lease, state["progress"])
                    else:
                        held = store.is_held(engine, job.id, self.owner)
                except CausalPlanError as exc:
                    logger.warning("cannot renew the lease of job %s: %s", job.id, exc.message)
                    continue
                if not held:
                    lose()
                    return

        def report(done: int, total: int) -> None:
            state["progress"] = (done, total)
            if self._stop.is_set():
                running.stop.set()
                raise JobCancelledError
            if not store.renew_lease(engine, job.id, self.owner, lease, (done, total)):
                lose()
                raise JobCancelledError

        with self._lock:
            self._running[job.id] = running
        beating = threading.Thread(target=heartbeat, name=f"causalplan-lease-{job.id}", daemon=True)
        beating.start()
        try:
            outcome = self._work(job, Progress(report, running.stop))
            made = outcome.file
            file = (made.data, made.content_type) if made is not None else None
            store.finish_job(engine, job.id, self.owner, keep, result=outcome.result, file=file)
        except JobCancelledError:
            if self._stop.is_set() and not lost.is_set():
                store.release_job(engine, job.id, self.owner)
        except CausalPlanError as exc:
            if self._stop.is_set():  # the pool closed under the job: another replica does it
                store.release_job(engine, job.id, self.owner)
            else:
                store.finish_job(engine, job.id, self.owner, keep, error=error_of(exc))
        finally:
            finished.set()
            beating.join()
            with self._lock:
                self._running.pop(job.id, None)
            running.ended.set()

    def _work(self, job: JobRecord, progress: Progress) -> Outcome:
        """Return the job's result and file; raise the CausalPlanError that failed it (a bug: internal_error)."""
        kind = KINDS[JobKind(job.kind)]  # claim_job takes only the kinds of KINDS
        try:
            done = kind.run(kind.read(job.request), self.services, progress)
            return done if isinstance(done, Outcome) else Outcome(done)
        except (CausalPlanError, JobCancelledError):
            raise
        except Exception as exc:
            logger.exception("job %s (%s) failed", job.id, job.kind)
            raise InternalError(
                f"The job failed on the server ({exc.__class__.__name__}); the log has the details."
            ) from exc
