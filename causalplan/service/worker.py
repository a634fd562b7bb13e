"""What runs inside a planner worker process: its loop, and the jobs the service sends it.

A worker serves one job at a time over its socket: it receives ``(function, args)``, runs it
and sends back ``("ok", value)``, ``("error", code, message, details)`` for a
``CausalPlanError``, or ``("crash", text)`` for anything else. Fast Downward's translator
forks from this process and its search binary starts from it, so the app's own process
(with uvicorn's threads) never does either.
"""

from __future__ import annotations

import gc
import importlib
import os
import resource
import signal
import sys
import traceback
from collections.abc import Callable
from contextlib import suppress
from functools import cache
from importlib import metadata
from importlib.util import find_spec
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

from causalplan.causal.model import CausalModel, Labelling
from causalplan.errors import CausalPlanError
from causalplan.objects.catalog import Catalog, load_catalog
from causalplan.pddl.task import build_task
from causalplan.planners import fd, pipeline
from causalplan.service.errors import PlannerOutOfMemoryError
from causalplan.transfer.verdict import evaluate_transfer

Job = tuple[Callable[..., Any], tuple[Any, ...]]
OPTIONAL_BACKENDS = ("unified_planning", "up_fast_downward", "up_pyperplan", "up_tamer", "pybullet", "matplotlib")
"""Modules some planners or commands use; /health reports the ones that fail to import."""


def main() -> None:
    """Run as a worker: ``argv`` holds the socket's file descriptor and the memory limit in MB."""
    descriptor, memory_mb = int(sys.argv[1]), int(sys.argv[2])
    serve(Connection(descriptor), memory_mb)


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
        except (EOFError, OSError):
            return
        if job is None:
            return
        function, args = job
        try:
            reply: tuple[Any, ...] = ("ok", function(*args))
        except CausalPlanError as exc:
            reply = ("error", exc.code, exc.message, exc.details)
        except MemoryError:
            reply = ("error", PlannerOutOfMemoryError.code, "The planner worker ran out of memory.", {})
        except Exception:  # noqa: BLE001 - reported to the service, which logs it and answers clearly
            reply = ("crash", traceback.format_exc())
        try:
            connection.send(reply)
        except (BrokenPipeError, OSError):
            return


def warm_up() -> None:
    """Do once, before the first job, what solves need: the translator imported, a search started, the catalog read.

    Work that would otherwise fall on each worker's first request. A planner that cannot run
    says so in its own answers (and /health), not here.
    """
    # Planners read no environment; these two wait for the settings module to take them over.
    override = os.environ.get("CAUSALPLAN_FD_BINARY")
    if override:
        fd.use_search_binary(Path(override))
    fd.keep_answers(int(os.environ.get("CAUSALPLAN_SOLVE_CACHE_SIZE", fd.SOLVE_CACHE_SIZE)))
    with suppress(Exception):
        importlib.import_module("fast_downward.translate.main")
    fd.prestart(fd.CONFIGS["fd"])  # the default search, waiting for its first task
    with suppress(CausalPlanError):
        worker_catalog(())


@cache
def worker_catalog(folders: tuple[Path, ...]) -> Catalog:
    """Return the catalog with the objects in ``folders``, read once per worker process."""
    return load_catalog(folders)


def plan_job(
    model: CausalModel,
    mapping: Labelling | None,
    planner: str,
    time_limit: float,
    catalog_folders: tuple[Path, ...],
) -> dict[str, object]:
    """Plan ``model`` (on the mapping's object if given); return ``PlanResult.as_dict()``.

    Without the PDDL: the service compiles that itself when a request asks for it.
    """
    catalog = worker_catalog(catalog_folders)
    target = catalog.get((mapping or model.labelling).object_id)
    result = pipeline.plan_task(build_task(model, target, mapping), planner, time_limit)
    return result.as_dict()


def transfer_job(
    model: CausalModel,
    mapping: Labelling,
    planner: str,
    time_limit: float,
    catalog_folders: tuple[Path, ...],
) -> dict[str, object]:
    """Return the transfer verdict of ``model`` through ``mapping``, as ``causalplan transfer --json``."""
    return evaluate_transfer(model, mapping, worker_catalog(catalog_folders), planner, time_limit).as_dict()


def _version(distribution: str) -> str | None:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return None


def probe_job() -> dict[str, object]:
    """Return what this worker can run: planner binaries, their versions, failed optional imports."""
    try:
        binary: str | None = str(fd.search_binary())
        binary_problem = None
    except CausalPlanError as exc:
        binary, binary_problem = None, exc.message
    failed: dict[str, str] = {}
    for module in OPTIONAL_BACKENDS:
        if find_spec(module) is None:
            failed[module] = "not installed"
            continue
        try:
            __import__(module)
        except Exception as exc:  # noqa: BLE001 - any import failure is what /health reports
            failed[module] = f"{exc.__class__.__name__}: {exc}"
    # The registry's own availability check imports unified-planning's engines, which is why
    # the probe runs in a throwaway process.
    problems = pipeline.planner_availability()
    return {
        "planners": [
            {"name": name, "available": problems.get(name) is None, "problem": problems.get(name)}
            for name in pipeline.PLANNERS
        ],
        "fast_downward": {
            "search_binary": binary,
            "search_binary_found": binary is not None,
            "problem": binary_problem,
            "translator_found": fd.translator_available(),
            "versions": {
                "up-fast-downward": _version("up-fast-downward"),
                "fast-downward-translate": _version("fast-downward.translate") or _version("fast-downward-translate"),
            },
        },
        "optional_backends_failed": failed,
    }


def simulate_job(
    model: CausalModel,
    mapping: Labelling | None,
    planner: str,
    time_limit: float,
    catalog_folders: tuple[Path, ...],
    picture: bool,
) -> dict[str, object]:
    """Plan ``model`` (on the mapping's object), run the plan in the physics simulator.

    Returns the plan (as ``causalplan plan --json``), the simulator's report and, when asked,
    the picture of the final assembly as a PNG data URL.
    """
    import base64

    from causalplan.sim import RenderMode, simulate_plan

    catalog = worker_catalog(catalog_folders)
    target = catalog.get((mapping or model.labelling).object_id)
    result = pipeline.plan_task(build_task(model, target, mapping), planner, time_limit)
    data: dict[str, object] = {"planning": result.as_dict(), "simulation": None, "image": None}
    if not result.has_plan:
        return data
    report = simulate_plan(target, result.steps, render=RenderMode.FINAL if picture else RenderMode.NONE)
    data["simulation"] = report.as_dict()
    if picture and report.picture is not None:
        data["image"] = "data:image/png;base64," + base64.b64encode(report.picture.png()).decode("ascii")
    return data
