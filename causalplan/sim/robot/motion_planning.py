"""Collision-free joint-space paths for the arm: a straight line when it is clear, else OMPL's RRTConnect.

OMPL (``pip install ompl``, nanobind bindings) does the planning; this module only states
the problem: the seven joints' bounds, a validity function of a state (supplied by the
caller, who knows the scene), start, goal and time limit. OMPL's random numbers are seeded
before every query, so the same query gives the same path.
"""

from __future__ import annotations

import importlib
import itertools
import math
from collections.abc import Callable, Sequence
from types import ModuleType

from causalplan.sim.robot.panda import Configuration
from causalplan.sim.scene import SimulatorUnavailableError

PLANNING_SECONDS = 2.0
"""The motion planner's time limit per query."""
SEED = 7
CHECK_STEP = 0.05
"""Radians (largest joint change) between two checked configurations of a path."""


def _ompl() -> tuple[ModuleType, ModuleType, ModuleType]:
    try:
        base = importlib.import_module("ompl.base")
        geometric = importlib.import_module("ompl.geometric")
        util = importlib.import_module("ompl.util")
    except ImportError as exc:
        raise SimulatorUnavailableError(f"The robot's motion planner needs OMPL ({exc}): pip install ompl") from None
    util.setLogLevel(util.LOG_NONE)
    return base, geometric, util


def densify(path: Sequence[Configuration], step: float = CHECK_STEP) -> list[Configuration]:
    """Return ``path`` with configurations added so no joint moves more than ``step`` between two."""
    dense: list[Configuration] = [tuple(path[0])]
    for a, b in itertools.pairwise(path):
        count = max(1, math.ceil(max(abs(y - x) for x, y in zip(a, b, strict=True)) / step))
        dense.extend(tuple(x + (y - x) * k / count for x, y in zip(a, b, strict=True)) for k in range(1, count + 1))
    return dense


def plan_path(
    start: Configuration,
    goal: Configuration,
    is_valid: Callable[[Configuration], bool],
    lower: Sequence[float],
    upper: Sequence[float],
    seconds: float = PLANNING_SECONDS,
    seed: int = SEED,
) -> list[Configuration] | None:
    """Return a collision-free path from ``start`` to ``goal`` (densified), or None when none was found.

    The straight line in joint space is tried first (most moves above a table are clear);
    OMPL's RRTConnect is asked only when it is not, and its answer is simplified.
    """
    line = densify([start, goal])
    if all(is_valid(configuration) for configuration in line):
        return line
    base, geometric, util = _ompl()
    util.RNG.setSeed(seed)
    space = base.RealVectorStateSpace(len(start))
    bounds = base.RealVectorBounds(len(start))
    for index, (low, high) in enumerate(zip(lower, upper, strict=True)):
        bounds.setLow(index, low)
        bounds.setHigh(index, high)
    space.setBounds(bounds)
    setup = geometric.SimpleSetup(space)
    setup.setStateValidityChecker(lambda state: is_valid(tuple(state[i] for i in range(len(start)))))
    setup.getSpaceInformation().setStateValidityCheckingResolution(0.005)
    ends = []
    for configuration in (start, goal):
        state = space.allocState()
        for index, angle in enumerate(configuration):
            state[index] = angle
        ends.append(state)
    setup.setStartAndGoalStates(ends[0], ends[1])
    setup.setPlanner(geometric.RRTConnect(setup.getSpaceInformation()))
    if not setup.solve(seconds) or not setup.haveExactSolutionPath():
        return None
    setup.simplifySolution()
    solution = setup.getSolutionPath()
    found = [tuple(solution.getState(k)[i] for i in range(len(start))) for k in range(solution.getStateCount())]
    dense = densify(found)
    return dense if all(is_valid(configuration) for configuration in dense) else None
