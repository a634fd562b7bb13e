"""The splitting solver's passes: the finer passes keep the proved success and never add attempts."""

from __future__ import annotations

import time

from causalplan.comparison.families import uncertain_tree
from causalplan.planners.mdp.model import compile_mdp, relevant_fits
from causalplan.planners.mdp.split import Splitter
from causalplan.planners.mdp.split_solve import solve_split
from causalplan.planners.result import PlanStatus


def test_the_finer_passes_keep_the_success_and_find_fewer_attempts() -> None:
    # Seed 0's tree: forcing every clean attempt tries parts a lazier policy would wait on.
    task = uncertain_tree(80, 15, 0)
    compiled = compile_mdp(task, relevant_fits(task))
    forced = Splitter(compiled, time.monotonic() + 60.0)
    start = forced.groups(compiled.base, 0, tuple(forced.support), forced.all_fits)
    assert start is not None
    success, attempts, _ = forced.combined(start)
    solution = solve_split(compiled, 60.0)
    assert solution is not None and solution.status is PlanStatus.SOLVED
    assert solution.success_probability is not None and solution.expected_actions is not None
    assert abs(solution.success_probability - success) < 1e-12
    assert solution.expected_actions < attempts - 0.1  # 8.55 against 9.21
