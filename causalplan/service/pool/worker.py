"""What runs inside a planner worker process: its start (pebble's initializer), each call, and its end.

``pebble`` starts, limits by time and kills the workers (``pool.PlannerPool``); here is only
what a worker does for itself. Its start (``initialize``) takes the app's environment (a fork
server's worker would otherwise have the server's, from when it started), sets the memory
limit, makes the worker's temp folder (its TMPDIR), imports and warms the planners once, and
says hello with its pid. A call (``run_call``) that may be stopped first says which worker took
it; each answers ``("ok", value)``, ``("error", code, message, details)`` for a
``CausalPlanError``, or ``("crash", text)`` for anything else (an exception of ours might not
unpickle in the app).

A worker stopped by pebble (SIGTERM: a time limit, a cancel, the pool closing) first kills its
children's process groups: by hand, because Fast Downward's searches run in sessions of their
own, which a signal to the worker misses. It then removes its temp folder. A worker killed
outright cannot; the app removes the folders of workers that no longer run (``remove_stale_folders``).
"""

from __future__ import annotations

import contextlib
import gc
import importlib
import os
import re
import resource
import shutil
import signal
import sys
import tempfile
import traceback
from collections.abc import Callable
from multiprocessing.connection import Connection
from pathlib import Path
from types import FrameType
from typing import Any

from causalplan import caches
from causalplan.errors import CausalPlanError
from causalplan.objects.catalog import Catalog
from causalplan.planners import fd, processes
from causalplan.service.errors import PlannerOutOfMemoryError
from causalplan.service.pool.catalog import worker_catalog
from causalplan.settings import Settings

FOLDER_PREFIX = "causalplan-worker-"
"""A worker's temp folder is ``causalplan-worker-<app pid>-<worker pid>-<random>``."""
_FOLDER_NAME = re.compile(re.escape(FOLDER_PREFIX) + r"(\d+)-(?:(\d+)-)?")

Message = tuple[str, int, int]
"""What a worker tells the app: ("ready", its pid, 0) once warm, ("started", its pid, run) per call."""
READY = "ready"
STARTED = "started"

_messages: list[Connection] = []
"""Where this worker's messages go: a pipe to the app, shared by its workers without a lock (a
message is one write of less than ``PIPE_BUF``, which the kernel keeps whole), so a worker
killed while it writes leaves no lock held. None for a probe's throwaway process."""


def is_running(pid: int) -> bool:
    """Return whether process ``pid`` runs (a zombie, dead but not yet reaped, does not)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in ("Z", "X")


def remove_stale_folders(root: Path | None = None) -> list[Path]:
    """Remove the temp folders of workers that no longer run, or whose app no longer runs; return them."""
    root = root or Path(tempfile.gettempdir())
    removed: list[Path] = []
    with contextlib.suppress(OSError):
        for folder in root.glob(FOLDER_PREFIX + "*"):
            match = _FOLDER_NAME.match(folder.name)
            if match is None or not folder.is_dir():
                continue
            app, worker = match.group(1), match.group(2)
            if is_running(int(app)) and (worker is None or is_running(int(worker))):
                continue
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
    return removed


SIMULATOR_MODULES = (
    "causalplan.sim.executor",
    "causalplan.sim.robot.mover",
    "causalplan.sim.robot.motion_planning",
    "causalplan.sim.robot.playback",
    "causalplan.transfer.robot_verdict",
)
"""What a robot's run imports: PyBullet, OMPL, TOPP-RA, SciPy and the robot's own modules."""
WARM_PICTURE_SIZE = (32, 24)
"""The warm-up picture's size: any size starts the renderer."""


def warm_simulator(catalog: Catalog | None) -> None:
    """Import the simulator and the robot's libraries now, as a worker starts (``warm_up``), and draw once.

    A worker's first "Watch the robot" then pays for its run only, not for seconds of imports,
    and its first picture (often a drawing made ahead, which a participant's plan may wait
    behind) not for PyBullet's, numpy's and Pillow's start: a small picture of the catalog's
    first part starts them. A simulator that cannot load says so in the answers that need it.
    """
    for module in SIMULATOR_MODULES:
        with contextlib.suppress(ImportError):
            importlib.import_module(module)
    if catalog is None or not catalog.objects:
        return
    from causalplan.sim.geometry import solids
    from causalplan.sim.render import part_alone

    part_id, solid = next(iter(solids(catalog.objects[min(catalog.objects)]).items()))
    with contextlib.suppress(CausalPlanError):  # no simulator: the pictures that need it say so
        part_alone(part_id, solid, WARM_PICTURE_SIZE)


def warm_up() -> None:
    """Do once, before the first call, what solves need: settings applied, translator imported, a search started.

    The catalog is read too. A planner that cannot run says so in its own answers (and /health).
    """
    settings = Settings()
    if settings.fd_binary is not None:
        fd.use_search_binary(settings.fd_binary)
    caches.fresh({"fd_answers": settings.solve_cache_size})  # this worker's own, sized by the settings
    with contextlib.suppress(Exception):  # a translator that cannot run says so in the answers (and /health)
        importlib.import_module("fast_downward.translate.main")
    fd.prestart(fd.CONFIGS["fd"])  # the default search, waiting for its first task
    catalog = None
    with contextlib.suppress(CausalPlanError):
        catalog = worker_catalog(())
    warm_simulator(catalog)  # so a worker's first robot run or picture starts at once


def initialize(
    app_pid: int,
    environment: dict[str, str],
    memory_mb: int,
    messages: Connection | None,
    quiet: bool,
) -> None:
    """Make this process a warm planner worker of app ``app_pid``; say hello on ``messages``."""
    os.environ.clear()
    os.environ.update(environment)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)  # C extensions print banners; errors still reach stderr (unless quiet)
    if quiet:
        os.dup2(devnull, 2)
    os.close(devnull)
    limit = processes.memory_limit(memory_mb)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    folder = Path(tempfile.mkdtemp(prefix=f"{FOLDER_PREFIX}{app_pid}-{os.getpid()}-"))
    # ``tempfile`` (and FD's processes, which inherit TMPDIR) put their folders in the worker's own.
    os.environ["TMPDIR"] = tempfile.tempdir = str(folder)
    signal.signal(signal.SIGTERM, lambda number, frame: _stop(folder, number, frame))
    warm_up()
    gc.collect()
    gc.freeze()  # what the worker imported stays: its collections then skip all of it
    if messages is not None:
        _messages.append(messages)
        messages.send((READY, os.getpid(), 0))


def _stop(folder: Path, number: int, _frame: FrameType | None) -> None:
    """Pebble stops this worker: take its children's process groups with it, remove its folder, exit."""
    processes.kill_children(os.getpid())
    shutil.rmtree(folder, ignore_errors=True)
    sys.stderr.flush()
    os._exit(128 + number)


def run_call(run: int | None, function: Callable[..., Any], args: tuple[Any, ...]) -> tuple[Any, ...]:
    """Return the reply: the function's value, its ``CausalPlanError``, or a bug's traceback.

    ``run``: the number of a call that may be stopped, whose caller must know which worker took it.
    """
    if run is not None:
        for messages in _messages:
            messages.send((STARTED, os.getpid(), run))
    try:
        return ("ok", function(*args))
    except CausalPlanError as exc:
        return ("error", exc.code, exc.message, exc.details)
    except MemoryError:
        return ("error", PlannerOutOfMemoryError.code, "The planner worker ran out of memory.", {})
    except Exception:  # noqa: BLE001 - reported to the app, which logs it and answers clearly
        return ("crash", traceback.format_exc())
