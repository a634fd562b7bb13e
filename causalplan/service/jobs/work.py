"""What every kind of job's work shares: the progress callback, the cancel signal, the planner pool."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeVar

from causalplan.service.errors import QueueFullError

if TYPE_CHECKING:
    from causalplan.service.deps import Services

T = TypeVar("T")


class JobCancelledError(Exception):
    """The job was cancelled (or its lease lost) while it ran: stop, store nothing."""


Progress = Callable[[int, int], None]
"""Called by a job's work with (done, total); raises JobCancelledError when the job is no longer ours."""


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
class Kind:
    """One kind of job: ``prepare`` checks a request at POST time, ``run`` does the work in a runner."""

    prepare: Callable[[dict[str, Any], Services], dict[str, Any]]
    run: Callable[[dict[str, Any], Services, Progress], dict[str, Any] | Outcome]


def in_pool(services: Services, function: Callable[..., T], args: tuple[Any, ...], timeout: float) -> T:
    """Return ``function(*args)`` run in a planner worker, waiting while interactive requests fill the queue.

    A job is not in a hurry: a full queue (QueueFullError) means wait and try again, not fail.
    """
    while True:
        try:
            return services.pool.run(function, args, timeout)
        except QueueFullError as exc:
            time.sleep(exc.retry_after)
