"""What runs inside a planner worker process: its loop over jobs from the app.

A worker serves one job at a time over its socket: it receives ``(function, args)``, says
``"started"``, runs it and sends back ``("ok", value)``, ``("error", code, message, details)``
for a ``CausalPlanError``, or ``("crash", text)`` for anything else. Fast Downward's translator
and search run in this process and its children, so the app's own process (with uvicorn's
threads) never does either.
"""

from __future__ import annotations

import gc
import os
import resource
import signal
import sys
import traceback
from collections.abc import Callable
from multiprocessing.connection import Connection
from typing import Any

from causalplan.errors import CausalPlanError
from causalplan.service.errors import PlannerOutOfMemoryError
from causalplan.service.pool.jobs import warm_up
from causalplan.service.pool.pool import STARTED

Job = tuple[Callable[..., Any], tuple[Any, ...]]


def main() -> None:
    """Run as a worker: ``argv`` holds the socket's file descriptor and the memory limit in MB."""
    descriptor, memory_mb = int(sys.argv[1]), int(sys.argv[2])
    serve(Connection(descriptor), memory_mb)


def run_job(function: Callable[..., Any], args: tuple[Any, ...]) -> tuple[Any, ...]:
    """Return the reply to one job: its value, its ``CausalPlanError``, or the traceback of a bug."""
    try:
        return ("ok", function(*args))
    except CausalPlanError as exc:
        return ("error", exc.code, exc.message, exc.details)
    except MemoryError:
        return ("error", PlannerOutOfMemoryError.code, "The planner worker ran out of memory.", {})
    except Exception:  # noqa: BLE001 - reported to the app, which logs it and answers clearly
        return ("crash", traceback.format_exc())


def serve(connection: Connection, memory_mb: int) -> None:
    """Say hello, then run jobs from ``connection`` until it closes or sends None."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C stops the server, which then stops us
    limit = memory_mb * 1024 * 1024
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    warm_up()
    gc.collect()
    gc.freeze()  # what the worker imported stays: its collections then skip all of it
    connection.send(("ready", os.getpid()))
    while True:
        try:
            job: Job | None = connection.recv()
            if job is None:
                return
            connection.send(STARTED)
            reply = run_job(*job)
            connection.send(reply)
        except (EOFError, OSError):  # the app closed the connection (or killed us meanwhile)
            return
