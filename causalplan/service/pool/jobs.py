"""The jobs the service sends its planner workers: plan, transfer, simulate, and the probe /health shows.

Each runs inside a worker process (``pool.worker``); arguments and answers are pickled, so they
are plain values (models, mappings, JSON-ready dicts).
"""

from __future__ import annotations

import importlib
import re
from contextlib import suppress
from importlib import metadata
from importlib.util import find_spec
from pathlib import Path

from causalplan import caches
from causalplan.causal.model import CausalModel, Labelling
from causalplan.errors import CausalPlanError
from causalplan.pddl.task import catalog_task
from causalplan.planners import fd, pipeline
from causalplan.service.pool import robot_jobs
from causalplan.service.pool.catalog import worker_catalog
from causalplan.settings import Settings
from causalplan.transfer.verdict import evaluate_transfer

OPTIONAL_BACKENDS = ("unified_planning", "up_fast_downward", "up_pyperplan", "up_tamer", "pybullet", "matplotlib")
"""Modules some planners or commands use; /health reports the ones that fail to import."""
FAST_DOWNWARD = "fd"
"""The registry's Fast Downward planner, whose availability /health reports."""


def warm_up() -> None:
    """Do once, before the first job, what solves need: settings applied, translator imported, a search started.

    The catalog is read too. A planner that cannot run says so in its own answers (and /health).
    """
    settings = Settings()
    if settings.fd_binary is not None:
        fd.use_search_binary(settings.fd_binary)
    caches.fresh({"fd_answers": settings.solve_cache_size})  # this worker's own, sized by the settings
    with suppress(Exception):  # a translator that cannot run says so in the answers (and /health)
        importlib.import_module("fast_downward.translate.main")
    fd.prestart(fd.CONFIGS["fd"])  # the default search, waiting for its first task
    with suppress(CausalPlanError):
        worker_catalog(())
    robot_jobs.warm_simulator()  # so a worker's first robot run for the 3D player starts at once


def plan_job(
    model: CausalModel,
    mapping: Labelling | None,
    planner: str,
    time_limit: float,
    catalog_folders: tuple[Path, ...],
    val: bool = False,
) -> dict[str, object]:
    """Plan ``model`` (on the mapping's object if given); return ``PlanResult.as_dict()``.

    Without the PDDL: the service compiles that itself when a request asks for it.
    """
    task = catalog_task(model, worker_catalog(catalog_folders), mapping)
    result = pipeline.plan_task(task, planner, time_limit, val=val)
    return result.as_dict()


def transfer_job(
    model: CausalModel,
    mapping: Labelling,
    planner: str,
    time_limit: float,
    catalog_folders: tuple[Path, ...],
    val: bool = False,
    robot: bool = False,
) -> dict[str, object]:
    """Return the transfer verdict of ``model`` through ``mapping``, as ``causalplan transfer --json``.

    ``robot``: the robot has the last word (``sim.robot_verdict.robot_judged``).
    """
    catalog = worker_catalog(catalog_folders)
    verdict = evaluate_transfer(model, mapping, catalog, planner, time_limit, val=val)
    if robot:
        from causalplan.transfer.robot_verdict import robot_judged

        verdict = robot_judged(verdict, catalog)
    return verdict.as_dict()


def _version(distribution: str) -> str | None:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return None


_PATH = re.compile(r"(?:/[^/\s'\"]+)+/([^/\s'\"]+)")


def without_paths(text: str | None) -> str | None:
    """Return ``text`` with each absolute path cut to its last part (/health says what, not where on disk)."""
    return None if text is None else _PATH.sub(r"\1", text)


def probe_job() -> dict[str, object]:
    """Return what this worker can run: the planner registry, Fast Downward, failed optional imports.

    Fast Downward is reported by whether its planner can run, never by where its binary is.
    """
    failed: dict[str, str] = {}
    for module in OPTIONAL_BACKENDS:
        if find_spec(module) is None:
            failed[module] = "not installed"
            continue
        try:
            __import__(module)
        except Exception as exc:  # noqa: BLE001 - any import failure is what /health reports
            failed[module] = f"{exc.__class__.__name__}: {without_paths(str(exc))}"
    # The registry's own availability check imports unified-planning's engines, which is why
    # the probe runs in a throwaway process.
    problems = {name: without_paths(problem) for name, problem in pipeline.planner_availability().items()}
    fd_problem = problems.get(FAST_DOWNWARD, f"the planner registry has no '{FAST_DOWNWARD}'")
    return {
        "planners": [
            {"name": name, "available": problems.get(name) is None, "problem": problems.get(name)}
            for name in pipeline.PLANNERS
        ],
        "fast_downward": {
            "available": fd_problem is None,
            "problem": fd_problem,
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
    robot: bool = False,
    val: bool = False,
    motors: bool = False,
) -> dict[str, object]:
    """Plan ``model`` (on the mapping's object), run the plan in the physics simulator.

    Returns the plan (as ``causalplan plan --json``), the simulator's report and, when asked,
    the picture of the final assembly as a PNG data URL. With ``robot`` the Panda carries out
    the plan (``robot``: whether it could, and why not); its film is a ``video`` job's
    (``service.jobs.video``), so ``video`` is None here. ``val``: VAL checks the plan too, as
    in ``plan_job``; ``motors``: with ``robot``, the motor commands are also
    driven through the Panda's joint motors in physics (``simulation.robot.motors``).
    """
    import base64

    from causalplan.service.pool.robot_jobs import robot_outcome
    from causalplan.sim import RenderMode, simulate_plan
    from causalplan.transfer.robot_verdict import robot_run

    task = catalog_task(model, worker_catalog(catalog_folders), mapping)
    target = task.obj
    result = pipeline.plan_task(task, planner, time_limit, val=val)
    data: dict[str, object] = {"planning": result.as_dict(), "simulation": None, "image": None}
    if not result.has_plan:
        return data
    if robot:
        report = robot_run(target, tuple(result.steps), motors)
        data.update(simulation=report.as_dict(), robot=robot_outcome(report), video=None)
        return data  # no still picture with the robot (its film is a video job's)
    report = simulate_plan(target, result.steps, render=RenderMode.FINAL if picture else RenderMode.NONE)
    data["simulation"] = report.as_dict()
    if picture and report.picture is not None:
        data["image"] = "data:image/png;base64," + base64.b64encode(report.picture.png()).decode("ascii")
    return data
