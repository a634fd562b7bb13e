"""Joint-space paths: the straight line when it is clear, OMPL's RRTConnect around an obstacle, seeded."""

from __future__ import annotations

import itertools

import pytest

from causalplan.sim.robot.motion_planning import CHECK_STEP, densify, plan_path

LOWER, UPPER = (-3.0,) * 7, (3.0,) * 7
START = (-1.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0)
GOAL = (1.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0)


def wall(configuration: tuple[float, ...]) -> bool:
    """A wall across joint 1 at 0 that only a detour through joint 2 above 1 gets past."""
    return not (abs(configuration[0]) < 0.2 and configuration[1] < 1.0)


def test_densify_keeps_every_joint_step_within_the_check_step() -> None:
    dense = densify([START, GOAL])
    assert dense[0] == START and dense[-1] == GOAL
    assert all(
        max(abs(b - a) for a, b in zip(p, q, strict=True)) <= CHECK_STEP + 1e-12 for p, q in itertools.pairwise(dense)
    )


def test_a_clear_straight_line_is_the_path() -> None:
    path = plan_path(START, GOAL, lambda configuration: True, LOWER, UPPER)
    assert path == densify([START, GOAL])


def test_around_an_obstacle_ompl_finds_a_valid_path_and_the_same_one_again() -> None:
    path = plan_path(START, GOAL, wall, LOWER, UPPER, seconds=5.0)
    assert path is not None
    assert path[0] == START and path[-1] == pytest.approx(GOAL)
    assert all(wall(configuration) for configuration in path)
    assert max(configuration[1] for configuration in path) >= 1.0  # it went round
    assert plan_path(START, GOAL, wall, LOWER, UPPER, seconds=5.0) == path


def test_an_enclosed_goal_has_no_path() -> None:
    def cage(configuration: tuple[float, ...]) -> bool:
        return not (0.5 < configuration[0] < 0.8)  # a shell joint 1 cannot cross

    assert plan_path(START, GOAL, cage, LOWER, UPPER, seconds=0.2) is None
