"""The registry of work: every function the service runs in a worker process, with its time limit and pool.

A ``Work`` names its function (typed arguments and the worker's catalog in, plain values out),
how long a worker may take for given arguments (``seconds``, from the settings), which pool it
runs on, and, for answers the service keeps, when an answer is final (``is_final``: a timeout
may go otherwise next time). ``WORK`` is the registry, by name (a plain dict, as pyperplan's
``SEARCHES``); each entry is also a constant (``PLAN``, ``TRANSFER``, ...) that callers pass to
``calls.Workers``. "Job" means only queued, leased work (``service.jobs``); some jobs do their
work here, on the jobs' pool.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Any, Generic, TypeVar

from causalplan.objects.catalog import Catalog
from causalplan.planners.result import PlanStatus
from causalplan.service.pool.catalog import worker_catalog
from causalplan.service.work import batches, pictures, planning, robot, troubleshooting
from causalplan.service.work.batches import ConsensusArguments, FitEstimateArguments, TrialsArguments
from causalplan.service.work.pictures import AssemblyPictureArguments, PartPicturesArguments
from causalplan.service.work.planning import (
    ExplanationArguments,
    PlanArguments,
    ProbeArguments,
    RepairArguments,
    SimulationArguments,
    TransferArguments,
)
from causalplan.service.work.robot import FitsFilmArguments, PlanFilmArguments, PlaybackArguments
from causalplan.service.work.troubleshooting import TroubleshootingArguments
from causalplan.settings import Settings
from causalplan.transfer.batch import TrialResult
from causalplan.transfer.verdict import Verdict

A = TypeVar("A")
R = TypeVar("R")

SIMULATION_SECONDS = 30.0
"""Time a worker gets for the simulation and its picture, beyond the planner's limit."""
PLANS_PER_EXPLANATION = 2
"""An explanation plans at most twice (the plan, and a why-not's alternative): its time limit is twice a plan's."""
PICTURE_SECONDS = 20.0
"""Longest a worker may take to draw an object's parts or a plan's result."""
PROBE_SECONDS = 60.0
"""Longest the probe's throwaway process may take (it imports every optional backend)."""
TRIAL_SECONDS = 0.1
"""A generous bound on one noisy insertion, for a fit's time limit in a worker (a trial is far quicker)."""
TROUBLESHOOTING_SECONDS = 30.0
"""Longest a worker may take for a troubleshooting table (a catalog object's takes milliseconds; the solve is
bounded by ``MAX_SERVICE_STATES``)."""
CONSENSUS_GRACE_SECONDS = 60.0
"""A consensus's worker may take this long beyond its trials' time limits (building, aligning)."""


class Pool(Enum):
    """Where work runs: the interactive requests' pool, the jobs' pool, or a throwaway process."""

    INTERACTIVE = "interactive"
    """Requests someone waits for: plans, transfers, checks, pictures, the robot's run for the player."""
    JOBS = "jobs"
    """Queued, leased work (``service.jobs``): a worker per runner thread, so no job takes an interactive worker."""
    ISOLATED = "isolated"
    """A fresh process that exits afterwards (the probe, which imports every optional backend)."""


@dataclass
class Work(Generic[A, R]):
    """One function run in a worker process: its arguments' type, its time limit and its pool.

    Not frozen, so a test can put a function of its own in an entry (``monkeypatch.setattr``).
    """

    name: str
    function: Callable[[A, Catalog], R]
    arguments: type[A]
    pool: Pool
    seconds: Callable[[A, Settings], float]
    """How long a worker may take for these arguments; then it is killed (and replaced)."""
    is_final: Callable[[R], bool] | None = None
    """For an answer the service keeps: whether this answer may be kept (None: never kept)."""


def perform(function: Callable[[A, Catalog], R], arguments: A, catalog_folders: tuple[Path, ...]) -> R:
    """Return ``function(arguments, catalog)`` with the catalog the worker read once (what a worker process calls)."""
    return function(arguments, worker_catalog(catalog_folders))


def _solve(limit: float, settings: Settings) -> float:
    return limit + settings.solve_grace_seconds


def _is_final_plan(data: dict[str, Any]) -> bool:
    return PlanStatus(str(data["status"])).is_final()


def _is_final_verdict(data: dict[str, Any]) -> bool:
    return bool(data["verdict"] != Verdict.UNDECIDED.value)


def _is_final_simulation(data: dict[str, Any]) -> bool:
    return isinstance(data["planning"], dict) and _is_final_plan(data["planning"])


PLAN: Work[PlanArguments, dict[str, Any]] = Work(
    "plan",
    planning.plan,
    PlanArguments,
    Pool.INTERACTIVE,
    lambda a, s: _solve(a.time_limit, s),
    _is_final_plan,
)
TRANSFER: Work[TransferArguments, dict[str, Any]] = Work(
    "transfer",
    planning.transfer,
    TransferArguments,
    Pool.INTERACTIVE,
    lambda a, s: _solve(a.time_limit, s) + (s.robot_seconds if a.robot else 0.0),
    _is_final_verdict,
)
SIMULATION: Work[SimulationArguments, dict[str, Any]] = Work(
    "simulation",
    planning.simulate,
    SimulationArguments,
    Pool.INTERACTIVE,
    lambda a, s: _solve(a.time_limit, s) + SIMULATION_SECONDS,
    _is_final_simulation,
)
EXPLANATION: Work[ExplanationArguments, dict[str, Any]] = Work(
    "explanation",
    planning.explanation,
    ExplanationArguments,
    Pool.INTERACTIVE,
    lambda a, s: PLANS_PER_EXPLANATION * a.time_limit + s.solve_grace_seconds,
)
REPAIRS: Work[RepairArguments, dict[str, Any] | None] = Work(
    "repairs",
    planning.repairs,
    RepairArguments,
    Pool.INTERACTIVE,
    lambda a, s: a.seconds + s.solve_grace_seconds,
)
PART_PICTURES: Work[PartPicturesArguments, dict[str, bytes]] = Work(
    "part_pictures", pictures.part_pictures, PartPicturesArguments, Pool.INTERACTIVE, lambda a, s: PICTURE_SECONDS
)
ASSEMBLY_PICTURE: Work[AssemblyPictureArguments, bytes] = Work(
    "assembly_picture",
    pictures.assembly_picture,
    AssemblyPictureArguments,
    Pool.INTERACTIVE,
    lambda a, s: PICTURE_SECONDS,
)
ROBOT_PLAYBACK: Work[PlaybackArguments, bytes] = Work(
    "robot_playback", robot.playback, PlaybackArguments, Pool.INTERACTIVE, lambda a, s: s.robot_seconds
)
TROUBLESHOOTING: Work[TroubleshootingArguments, dict[str, Any]] = Work(
    "troubleshooting",
    troubleshooting.troubleshoot,
    TroubleshootingArguments,
    Pool.INTERACTIVE,
    lambda a, s: TROUBLESHOOTING_SECONDS,
    lambda data: True,  # exact and deterministic: the same arguments, the same answer
)
PROBE: Work[ProbeArguments, dict[str, object]] = Work(
    "probe", planning.probe, ProbeArguments, Pool.ISOLATED, lambda a, s: PROBE_SECONDS
)
QUEUED_SIMULATION: Work[SimulationArguments, dict[str, Any]] = Work(
    "queued_simulation",
    planning.simulate,
    SimulationArguments,
    Pool.JOBS,
    lambda a, s: _solve(a.time_limit, s) + (s.robot_seconds if a.robot else 0.0),
)
QUEUED_TROUBLESHOOTING: Work[TroubleshootingArguments, dict[str, Any]] = Work(
    "queued_troubleshooting",
    troubleshooting.troubleshoot,
    TroubleshootingArguments,
    Pool.JOBS,
    lambda a, s: TROUBLESHOOTING_SECONDS + s.robot_seconds,
)
FILM_OF_FITS: Work[FitsFilmArguments, dict[str, Any]] = Work(
    "film_of_fits", robot.film_of_fits, FitsFilmArguments, Pool.JOBS, lambda a, s: s.robot_seconds
)
FILM_OF_PLAN: Work[PlanFilmArguments, dict[str, Any]] = Work(
    "film_of_plan",
    robot.film_of_plan,
    PlanFilmArguments,
    Pool.JOBS,
    lambda a, s: _solve(a.time_limit, s) + s.robot_seconds,
)
FIT_ESTIMATE: Work[FitEstimateArguments, dict[str, Any]] = Work(
    "fit_estimate",
    batches.fit_estimate,
    FitEstimateArguments,
    Pool.JOBS,
    lambda a, s: s.robot_seconds + a.trials * TRIAL_SECONDS,
)
JUDGED_TRIALS: Work[TrialsArguments, list[TrialResult]] = Work(
    "judged_trials",
    batches.judged_trials,
    TrialsArguments,
    Pool.JOBS,
    lambda a, s: len(a.trials) * _solve(a.time_limit, s),
)
CONSENSUS: Work[ConsensusArguments, dict[str, Any]] = Work(
    "consensus",
    batches.consensus_report,
    ConsensusArguments,
    Pool.JOBS,
    # Every member's trial plus one per test object may each take the time limit.
    lambda a, s: (a.count + 8) * _solve(a.time_limit, s) + CONSENSUS_GRACE_SECONDS,
)

WORK: dict[str, Work[Any, Any]] = {
    work.name: work
    for work in (
        PLAN,
        TRANSFER,
        SIMULATION,
        EXPLANATION,
        REPAIRS,
        PART_PICTURES,
        ASSEMBLY_PICTURE,
        ROBOT_PLAYBACK,
        TROUBLESHOOTING,
        PROBE,
        QUEUED_SIMULATION,
        FILM_OF_FITS,
        FILM_OF_PLAN,
        QUEUED_TROUBLESHOOTING,
        FIT_ESTIMATE,
        JUDGED_TRIALS,
        CONSENSUS,
    )
}
"""Every function the service runs in a worker process, by name."""
