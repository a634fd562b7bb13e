"""Fit probabilities measured in physics: many robot insertions of each fit with the part held a little off.

For each fit of an object, the robot makes just that joint once: the fixed part stands where
the assembly puts it (with the parts that hold it to the base), the moving part waits on the
table, and the Panda fetches it, carries it and
drives it home along the connector axis (``sim.robot``). The robot does not feel where the
part sits in its fingers, so its commands are the same in every trial; what changes is the
grasp: each trial moves the part in the gripper by a random offset (a normal distribution
of ``noise_mm`` per axis) and turn (``noise_deg`` about a random axis). The trial then moves
the part where those commands take it, position by position: where it overlaps the table or
a part in place before the push home, it jams (``blocked_path``); at the end it measures how
far its connector is from the seat across the axis (the push home takes up the error along
it) and how tilted. It succeeds when both are within the fit's own tolerance
(``tolerance_mm``/``tolerance_deg`` in the catalog, how forgiving the connector is: a thread
less than a clip), else it fails ``misaligned``; a part more than the grasp tolerance off
fails ``grasp_lost``, and when the robot cannot do the joint at all, every trial fails with
the robot's code.

Each fit's noises come from one seeded stream and are all drawn before any trial runs, so the
trials can go in chunks (``estimate_fits(..., map_chunks=...)``, e.g. on a Dask cluster) with
the numbers of the run in one process.
"""

from __future__ import annotations

import math
import random
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from causalplan.objects.model import AssemblyObject, Fit
from causalplan.sim.checks import ALIGNMENT_TOLERANCE_DEG, ALIGNMENT_TOLERANCE_MM, PENETRATION_TOLERANCE_MM
from causalplan.sim.geometry import Solid, solids
from causalplan.sim.layout import ROBOT_ROW_GAP, designed_poses, layout
from causalplan.sim.motions import MOTIONS, approach_path, approach_start
from causalplan.sim.plan_steps import StepRequest
from causalplan.sim.poses import Pose, about_axis, angle_between, dot, normalized, scale
from causalplan.sim.report import Failure
from causalplan.sim.robot.robot import Robot
from causalplan.sim.robot.steps import PUSH_DEPTH, bring, drive
from causalplan.sim.scene import Scene

DEFAULT_TRIALS = 200
DEFAULT_NOISE_MM = 1.0
DEFAULT_NOISE_DEG = 1.0
CONFIDENCE = 0.95
GRASP_TOLERANCE_MM = 3.0
GRASP_TOLERANCE_DEG = 5.0
"""How far a part may sit off its grasp in the gripper before the fingers lose it."""


@dataclass(frozen=True)
class FitEstimate:
    """A fit's measured success rate, its 95% Wilson interval, and how the failed trials failed."""

    fit: str
    trials: int
    successes: int
    interval: tuple[float, float]
    failures: dict[str, int] = field(default_factory=dict)
    timing: dict[str, float] = field(default_factory=dict, compare=False)
    """Seconds of the robot's nominal run ("robot") and of the trials ("trials")."""

    @property
    def probability(self) -> float:
        return self.successes / self.trials

    def as_dict(self) -> dict[str, object]:
        """Return the JSON-ready form: id, trials, successes, probability, interval, failures."""
        return {
            "id": self.fit,
            "trials": self.trials,
            "successes": self.successes,
            "probability": round(self.probability, 4),
            "interval": [round(self.interval[0], 4), round(self.interval[1], 4)],
            "failures": dict(sorted(self.failures.items(), key=lambda item: (-item[1], item[0]))),
        }


def wilson_interval(successes: int, trials: int) -> tuple[float, float]:
    """Return the 95% Wilson score interval of a success rate (statsmodels' ``proportion_confint``)."""
    from statsmodels.stats.proportion import proportion_confint

    low, high = proportion_confint(successes, trials, alpha=1 - CONFIDENCE, method="wilson")
    return float(low), float(high)


def _noise(chance: random.Random, noise_mm: float, noise_deg: float) -> Pose:
    """Return a random grasp error: an offset (metres) and a turn about a random axis."""
    offset = tuple(chance.gauss(0.0, noise_mm / 1000) for _ in range(3))
    axis = normalized(tuple(chance.gauss(0.0, 1.0) for _ in range(3)))  # type: ignore[arg-type]
    angle = math.radians(chance.gauss(0.0, noise_deg)) if noise_deg > 0 else 0.0
    return Pose(offset, about_axis(axis, angle))  # type: ignore[arg-type]


def _prerequisites(obj: AssemblyObject, fit: Fit) -> list[Fit]:
    """Return fits that put the fit's fixed part in the assembly, from the base out (catalog order decides)."""
    chain: list[Fit] = []
    part = fit.fixed_part
    while part != obj.base:
        before = next(
            (f for f in obj.fits if f.moving_part == part and not MOTIONS[f.primitive].touches_only and f not in chain),
            None,
        )
        if before is None:
            break
        chain.insert(0, before)
        part = before.fixed_part
    return chain


def _request(fit: Fit) -> StepRequest:
    return StepRequest(fit.primitive, fit.moving_part, fit.fixed_part, fit.id)


@dataclass
class _Insertion:
    """The robot's nominal run of one fit, with the scene kept for the trials."""

    scene: Scene
    fit: Fit
    fixed_pose: Pose
    obstacles: list[int]
    """The bodies the part may jam against: the table and the parts in place."""
    line: list[tuple[Pose, Pose, float]] = field(default_factory=list)
    """At every commanded position of the drive home: the part's pose, the grasp, and metres to the seat."""
    failure: str | None = None


def _nominal_run(obj: AssemblyObject, fit: Fit, parts: dict[str, Solid], scene: Scene) -> _Insertion:
    """Have the robot make the fit once, without noise, on the assembly it needs (built in ``scene``).

    The parts the fit needs in place (its fixed part and what holds it to the base) stand at
    their seats; the moving part waits on the table.
    """
    built = [_request(before) for before in _prerequisites(obj, fit)]
    requests = (*built, _request(fit))
    homes, _ = layout(obj, parts, requests, ROBOT_ROW_GAP)
    seats = designed_poses(obj, parts, requests)
    present = [obj.base, *(request.moving for request in built if request.moving != obj.base), fit.fixed_part]
    moving, fixed = parts[fit.moving_part], parts[fit.fixed_part]
    motion = MOTIONS[fit.primitive]
    fixed_pose = seats.get(fit.fixed_part, homes[fit.fixed_part])
    for part in dict.fromkeys(present):
        scene.add_part(part, seats.get(part, homes[part]), dynamic=False)
    scene.add_part(fit.moving_part, homes[fit.moving_part], dynamic=False)
    insertion = _Insertion(scene, fit, fixed_pose, [scene.ground, *(scene.bodies[part] for part in set(present))])
    moving_frame, fixed_frame = moving.frames[fit.moving_connector], fixed.frames[fit.fixed_connector]
    path = approach_path(fixed_pose, moving_frame, fixed_frame, motion)
    scene.place(fit.moving_part, path(0.0))
    axis = fixed_pose.turn(fixed_frame.axis)
    start = approach_start(scene.bounds([fit.moving_part]), scene.bounds(present), axis)
    scene.place(fit.moving_part, homes[fit.moving_part])
    seat = fixed_pose.apply(fixed_frame.position)
    robot = Robot(scene)
    robot.step = 1
    failed = bring(robot, fit.moving_part, obj.part(fit.moving_part), motion, path, start, fit.fixed_part)
    if failed is None:

        def record() -> None:
            if robot.held is not None:
                pose = scene.pose(fit.moving_part)
                to_seat = dot(tuple(a - b for a, b in zip(pose.apply(moving_frame.position), seat, strict=True)), axis)  # type: ignore[arg-type]
                insertion.line.append((pose, robot.held.grasp, to_seat))

        robot.observe = record
        failed = drive(robot, motion, path, start, 0.0, moving.name, fit.fixed_part)
    if failed is not None or robot.held is None or not insertion.line:
        insertion.failure = failed.failure.value if failed else Failure.GRASP_LOST.value
    return insertion


def _trial(insertion: _Insertion, parts: dict[str, Solid], noise: Pose) -> str | None:
    """Return how one noisy insertion failed, or None when the connector engaged.

    The part follows the robot's commands with ``noise`` in the gripper; it jams (fails
    ``blocked_path``) where it overlaps the table or a part in place before the push home;
    at the end its connector must be within the fit's tolerance of the seat, across the axis.
    """
    fit, scene = insertion.fit, insertion.scene
    moved, turned = noise.position, 2 * math.acos(min(1.0, abs(noise.orientation[3])))
    if math.sqrt(dot(moved, moved)) * 1000 > GRASP_TOLERANCE_MM or math.degrees(turned) > GRASP_TOLERANCE_DEG:
        return Failure.GRASP_LOST.value
    tolerance = PENETRATION_TOLERANCE_MM / 1000
    part_pose = Pose()
    for nominal, grasp, to_seat in insertion.line:
        part_pose = nominal * grasp * noise.inverse() * grasp.inverse()
        if to_seat > PUSH_DEPTH:
            scene.place(fit.moving_part, part_pose)
            if scene.deepest_overlap(fit.moving_part, insertion.obstacles)[0] > tolerance:
                return Failure.BLOCKED_PATH.value
    moving_frame = parts[fit.moving_part].frames[fit.moving_connector]
    fixed_frame = parts[fit.fixed_part].frames[fit.fixed_connector]
    fixed_pose = insertion.fixed_pose
    axis = fixed_pose.turn(fixed_frame.axis)
    gap = [
        a - b
        for a, b in zip(part_pose.apply(moving_frame.position), fixed_pose.apply(fixed_frame.position), strict=True)
    ]
    along = dot(gap, axis)  # type: ignore[arg-type]
    across = math.sqrt(max(0.0, dot(gap, gap) - along * along)) * 1000  # type: ignore[arg-type]
    tilt = math.degrees(angle_between(part_pose.turn(moving_frame.axis), scale(axis, -1.0)))
    tolerance_mm = fit.tolerance_mm if fit.tolerance_mm is not None else ALIGNMENT_TOLERANCE_MM
    tolerance_deg = fit.tolerance_deg if fit.tolerance_deg is not None else ALIGNMENT_TOLERANCE_DEG
    return None if across <= tolerance_mm and tilt <= tolerance_deg else Failure.MISALIGNED.value


def draw_noises(obj: AssemblyObject, fit: Fit, trials: int, seed: int, noise_mm: float, noise_deg: float) -> list[Pose]:
    """Return the grasp errors of the fit's ``trials`` insertions, in order, from its own seeded stream.

    Every noise is drawn before any trial runs, so cutting the trials into chunks (on a
    cluster) cannot change which insertion gets which noise.
    """
    chance = random.Random(f"{seed}:{obj.id}:{fit.id}")
    return [_noise(chance, noise_mm, noise_deg) for _ in range(trials)]


@dataclass(frozen=True)
class InsertionChunk:
    """Some of one fit's noisy insertions, as one task: the object, the fit, the grasp errors to try."""

    obj: AssemblyObject
    fit_id: str
    noises: tuple[Pose, ...]


@dataclass(frozen=True)
class ChunkOutcome:
    """How a chunk's insertions went: how many, how many engaged, how the others failed, and seconds spent."""

    fit: str
    trials: int
    successes: int
    failures: dict[str, int]
    timing: dict[str, float]


ChunkMapper = Callable[
    [Callable[[InsertionChunk], ChunkOutcome], Sequence[InsertionChunk], Callable[[ChunkOutcome], None] | None],
    list[ChunkOutcome],
]
"""Runs a top-level function on every chunk and returns the outcomes in the chunks' order, calling the
third argument with each outcome as it comes (e.g. ``transfer.cluster.map_on_cluster`` on a chosen
cluster; passed in, since ``sim`` knows nothing of the cluster)."""

DEFAULT_CHUNK_INSERTIONS = 1000
"""Insertions per cluster task. Each task makes the robot's nominal run again (it is deterministic,
so every chunk sees the same one) before its trials, so a chunk holds many trials to make that
repeated run a small share of the task."""


def _insert(obj: AssemblyObject, fit: Fit, noises: Sequence[Pose]) -> ChunkOutcome:
    """Return the outcome of one noisy insertion of ``fit`` per noise, after the robot's nominal run."""
    parts = solids(obj)
    scene_parts = {part: parts[part] for part in obj.part_ids}
    with Scene(scene_parts, drawn=False) as scene:
        started = time.perf_counter()
        insertion = _nominal_run(obj, fit, parts, scene)
        timing = {"robot": time.perf_counter() - started}
        if insertion.failure is not None:
            return ChunkOutcome(fit.id, len(noises), 0, {insertion.failure: len(noises)}, {**timing, "trials": 0.0})
        started = time.perf_counter()
        failures: dict[str, int] = {}
        successes = 0
        for noise in noises:
            failed = _trial(insertion, parts, noise)
            if failed is None:
                successes += 1
            else:
                failures[failed] = failures.get(failed, 0) + 1
        timing["trials"] = time.perf_counter() - started
    return ChunkOutcome(fit.id, len(noises), successes, failures, timing)


def insert_chunk(chunk: InsertionChunk) -> ChunkOutcome:
    """Return the outcome of a chunk's insertions (the task a cluster worker runs)."""
    return _insert(chunk.obj, chunk.obj.fit(chunk.fit_id), chunk.noises)


def _estimate(fit_id: str, outcomes: Sequence[ChunkOutcome]) -> FitEstimate:
    """Return the fit's estimate from its chunks' outcomes (sums: the chunks' order does not matter)."""
    trials = sum(outcome.trials for outcome in outcomes)
    successes = sum(outcome.successes for outcome in outcomes)
    failures: dict[str, int] = {}
    timing: dict[str, float] = {}
    for outcome in outcomes:
        for code, count in outcome.failures.items():
            failures[code] = failures.get(code, 0) + count
        for what, seconds in outcome.timing.items():
            timing[what] = timing.get(what, 0.0) + seconds
    return FitEstimate(fit_id, trials, successes, wilson_interval(successes, trials), failures, timing)


def estimate_fit(
    obj: AssemblyObject,
    fit: Fit,
    trials: int = DEFAULT_TRIALS,
    seed: int = 0,
    noise_mm: float = DEFAULT_NOISE_MM,
    noise_deg: float = DEFAULT_NOISE_DEG,
) -> FitEstimate:
    """Return the fit's success rate over ``trials`` noisy insertions (the same seed, the same numbers)."""
    return _estimate(fit.id, [_insert(obj, fit, draw_noises(obj, fit, trials, seed, noise_mm, noise_deg))])


def estimate_fits(
    obj: AssemblyObject,
    trials: int = DEFAULT_TRIALS,
    seed: int = 0,
    noise_mm: float = DEFAULT_NOISE_MM,
    noise_deg: float = DEFAULT_NOISE_DEG,
    fit_ids: Sequence[str] = (),
    *,
    map_chunks: ChunkMapper | None = None,
    chunk_size: int = DEFAULT_CHUNK_INSERTIONS,
    progress: Callable[[int], None] | None = None,
) -> list[FitEstimate]:
    """Return the estimate of every fit of ``obj`` (or of ``fit_ids``), in catalog order.

    Without ``map_chunks`` the fits are measured here, one after another. With it, every fit's
    insertions are cut into chunks of ``chunk_size`` and ``map_chunks`` runs them (e.g. on a
    Dask cluster, all fits at once); the numbers are those of the run here, for the same seed.
    ``progress`` is called with how many insertions were just done (per fit here, per chunk there).
    """
    chosen = [fit for fit in obj.fits if not fit_ids or fit.id in fit_ids]
    if map_chunks is None:
        estimates = []
        for fit in chosen:
            estimates.append(estimate_fit(obj, fit, trials, seed, noise_mm, noise_deg))
            if progress is not None:
                progress(trials)
        return estimates
    if chunk_size < 1:
        raise ValueError(f"The chunk size must be at least 1; got {chunk_size}.")
    tasks = []
    for fit in chosen:
        noises = draw_noises(obj, fit, trials, seed, noise_mm, noise_deg)
        tasks += [
            InsertionChunk(obj, fit.id, tuple(noises[start : start + chunk_size]))
            for start in range(0, trials, chunk_size)
        ]

    def done(outcome: ChunkOutcome) -> None:
        if progress is not None:
            progress(outcome.trials)

    outcomes = map_chunks(insert_chunk, tasks, done)
    return [_estimate(fit.id, [outcome for outcome in outcomes if outcome.fit == fit.id]) for fit in chosen]
