"""What a worker process runs to answer a model: plan, transfer, simulate, explain, repair; and the probe.

Each function takes its typed arguments and the catalog the worker read once
(``pool.catalog.worker_catalog``), and returns plain values (JSON-ready dicts): both cross a
process boundary pickled. The registry (``registry``) says how long each may take and on which
pool it runs; ``calls.Workers`` runs them.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass
from importlib import metadata
from importlib.util import find_spec

from causalplan.causal.model import CausalModel, Labelling
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import catalog_task
from causalplan.planners import pipeline
from causalplan.transfer.verdict import Verdict, evaluate_transfer

OPTIONAL_BACKENDS = ("unified_planning", "up_fast_downward", "up_pyperplan", "up_tamer", "pybullet", "matplotlib")
"""Modules some planners or commands use; /health reports the ones that fail to import."""
FAST_DOWNWARD = "fd"
"""The registry's Fast Downward planner, whose availability /health reports."""


@dataclass(frozen=True)
class PlanArguments:
    """A plan of ``model`` (on the mapping's object if given); ``val``: VAL checks it too."""

    model: CausalModel
    mapping: Labelling | None
    planner: str
    time_limit: float
    val: bool = False


@dataclass(frozen=True)
class TransferArguments:
    """A transfer of ``model`` through ``mapping``; ``robot``: the robot has the last word."""

    model: CausalModel
    mapping: Labelling
    planner: str
    time_limit: float
    val: bool = False
    robot: bool = False


@dataclass(frozen=True)
class SimulationArguments:
    """A plan run in the simulator: with its final ``picture``, or carried out by the ``robot`` (and its ``motors``)."""

    model: CausalModel
    mapping: Labelling | None
    planner: str
    time_limit: float
    picture: bool
    robot: bool = False
    val: bool = False
    motors: bool = False


@dataclass(frozen=True)
class ExplanationArguments:
    """An explanation of the plan: ``why`` a step is there, ``why_not`` another; ``simulate`` the plans too."""

    model: CausalModel
    mapping: Labelling | None
    planner: str
    time_limit: float
    why: str | None
    why_not: str | None
    val: bool = False
    simulate: bool = False


@dataclass(frozen=True)
class RepairArguments:
    """A search for repairs of a transfer of ``model`` through ``mapping`` that fails."""

    model: CausalModel
    mapping: Labelling
    planner: str
    time_limit: float
    val: bool = False
    seconds: float = 10.0
    """The whole search's budget, whatever ``time_limit`` is: it stops there with what it found."""


@dataclass(frozen=True)
class ProbeArguments:
    """The probe takes nothing: it reports what a worker can run."""


def plan(arguments: PlanArguments, catalog: Catalog) -> dict[str, object]:
    """Return ``PlanResult.as_dict()`` (without the PDDL: the service compiles that itself when asked)."""
    task = catalog_task(arguments.model, catalog, arguments.mapping)
    return pipeline.plan_task(task, arguments.planner, arguments.time_limit, val=arguments.val).as_dict()


def transfer(arguments: TransferArguments, catalog: Catalog) -> dict[str, object]:
    """Return the transfer verdict, as ``causalplan transfer --json``."""
    model, mapping, planner, limit = arguments.model, arguments.mapping, arguments.planner, arguments.time_limit
    verdict = evaluate_transfer(model, mapping, catalog, planner, limit, val=arguments.val)
    if arguments.robot:
        from causalplan.transfer.robot_verdict import robot_judged

        verdict = robot_judged(verdict, catalog)
    return verdict.as_dict()


def simulate(arguments: SimulationArguments, catalog: Catalog) -> dict[str, object]:
    """Plan, then run the plan in the physics simulator.

    Returns the plan (as ``causalplan plan --json``), the simulator's report and, when asked,
    the picture of the final assembly as a PNG data URL. With ``robot`` the Panda carries out
    the plan (``robot``: whether it could, and why not); its film is a ``video`` job's, so
    ``video`` is None here. ``motors``: with ``robot``, the motor commands are also driven
    through the Panda's joint motors in physics (``simulation.robot.motors``).
    """
    import base64

    from causalplan.service.work.robot import robot_outcome
    from causalplan.sim import RenderMode, simulate_plan
    from causalplan.transfer.robot_verdict import robot_run

    task = catalog_task(arguments.model, catalog, arguments.mapping)
    result = pipeline.plan_task(task, arguments.planner, arguments.time_limit, val=arguments.val)
    data: dict[str, object] = {"planning": result.as_dict(), "simulation": None, "image": None}
    if not result.has_plan:
        return data
    if arguments.robot:
        report = robot_run(task.obj, tuple(result.steps), arguments.motors)
        data.update(simulation=report.as_dict(), robot=robot_outcome(report), video=None)
        return data  # no still picture with the robot (its film is a video job's)
    render = RenderMode.FINAL if arguments.picture else RenderMode.NONE
    report = simulate_plan(task.obj, result.steps, render=render)
    data["simulation"] = report.as_dict()
    if arguments.picture and report.picture is not None:
        data["image"] = "data:image/png;base64," + base64.b64encode(report.picture.png()).decode("ascii")
    return data


def explanation(arguments: ExplanationArguments, catalog: Catalog) -> dict[str, object]:
    """Return ``causalplan explain --json`` for the plan of the model (on the mapping's object if given)."""
    from causalplan.explain.explanation import explain_plan

    task = catalog_task(arguments.model, catalog, arguments.mapping)
    why, why_not = arguments.why, arguments.why_not
    return explain_plan(
        task, why, why_not, arguments.planner, arguments.time_limit, arguments.val, arguments.simulate
    ).as_dict()


def repairs(arguments: RepairArguments, catalog: Catalog) -> dict[str, object] | None:
    """Return the repairs of a failed transfer (``RepairSearch.as_dict()``), or None when it does not fail."""
    from causalplan.explain.repair import search_repairs

    deadline = time.monotonic() + arguments.seconds
    model, mapping, planner, limit = arguments.model, arguments.mapping, arguments.planner, arguments.time_limit
    verdict = evaluate_transfer(model, mapping, catalog, planner, min(limit, arguments.seconds), val=arguments.val)
    if verdict.verdict is not Verdict.FAILS:
        return None
    left = max(0.0, deadline - time.monotonic())
    search = search_repairs(
        model, mapping, catalog, verdict, planner=planner, time_limit=limit, val=arguments.val, seconds=left
    )
    return search.as_dict()


def _version(distribution: str) -> str | None:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return None


_PATH = re.compile(r"(?:/[^/\s'\"]+)+/([^/\s'\"]+)")


def without_paths(text: str | None) -> str | None:
    """Return ``text`` with each absolute path cut to its last part (/health says what, not where on disk)."""
    return None if text is None else _PATH.sub(r"\1", text)


def probe(arguments: ProbeArguments, catalog: Catalog) -> dict[str, object]:
    """Return what this worker can run: the planner registry, Fast Downward, failed optional imports.

    Fast Downward is reported by whether its planner can run, never by where its binary is.
    """
    del arguments, catalog
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
