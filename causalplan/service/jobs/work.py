"""What every kind of job's work shares: the progress callback, the cancel signal, the jobs' workers."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from pydantic import BaseModel

from causalplan.service.errors import WorkerDiedError
from causalplan.service.jobs.requests import JobRequest
from causalplan.service.work.calls import WorkStoppedError
from causalplan.service.work.registry import Work

if TYPE_CHECKING:
    from causalplan.service.deps import Services

logger = logging.getLogger(__name__)

A = TypeVar("A")
T = TypeVar("T")
B = TypeVar("B", bound=BaseModel)
R = TypeVar("R", bound=JobRequest)


class JobCancelledError(Exception):
    """The job was cancelled (or its lease lost) while it ran: stop, store nothing."""


@dataclass(frozen=True)
class Progress:
    """What a job's work reports its progress to, and hears a cancel from.

    Called with (done, total): raises JobCancelledError once ``stop`` is set (the job was
    cancelled, its lease lost, or the replica stops), or when ``report`` finds the job no
    longer ours. ``stop`` also kills the job's worker at once (``in_pool``).
    """

    report: Callable[[int, int], None]
    stop: threading.Event = field(default_factory=threading.Event)

    def __call__(self, done: int, total: int) -> None:
        if self.stop.is_set():
            raise JobCancelledError
        self.report(done, total)


@dataclass(frozen=True)
class JobFile:
    """A file a job made (the robot's film), stored with the job and served at its URL."""

    data: bytes
    content_type: str


@dataclass(frozen=True)
class Outcome:
    """What a job's work returns when it made a file too: the JSON result and the file."""

    result: dict[str, Any]
    file: JobFile | None = None


@dataclass(frozen=True)
class Kind(Generic[B, R]):
    """One kind of job: ``prepare`` checks the API's body at POST time and returns the request to
    store; ``read`` reads it back from the job's row; ``run`` does the work in a runner."""

    prepare: Callable[[B, Services], R]
    read: Callable[[Any], R]
    run: Callable[[R, Services, Progress], dict[str, Any] | Outcome]


def in_pool(services: Services, progress: Progress, work: Work[A, T], arguments: A) -> T:
    """Return ``work`` done on ``arguments`` by the work layer, in a worker of the jobs' pool.

    Once the job is stopped (``progress.stop``), its worker is killed and this raises
    JobCancelledError; a full pool is waited for (``Workers.queued_call``).
    """
    try:
        return services.work.run(work, arguments, stop=progress.stop)
    except WorkStoppedError:
        raise JobCancelledError from None


def in_pool_retried(services: Services, progress: Progress, work: Work[A, T], arguments: A) -> T:
    """Return ``work`` done on ``arguments`` as ``in_pool`` does; when its worker dies, once more on a fresh worker.

    The pool replaces a dead worker at once. A second death raises its ``WorkerDiedError``; a
    closed pool or a call no worker could take (other ``WorkerCrashedError``s) is not run again.
    """
    try:
        return in_pool(services, progress, work, arguments)
    except WorkerDiedError as exc:
        if progress.stop.is_set():
            raise
        logger.warning("a job worker died (exit code %s): its work runs once more", exc.details["exit_code"])
        return in_pool(services, progress, work, arguments)
