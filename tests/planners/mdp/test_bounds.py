"""The admissible bound: each shared holder counted once is tighter than counting it nowhere, and still a bound."""

from __future__ import annotations

import pytest

from causalplan.comparison.families import with_probabilities
from causalplan.comparison.synthetic import synthetic_task
from causalplan.planners.mdp.bounds import bound
from causalplan.planners.mdp.exact import solve_compiled_mdp
from causalplan.planners.mdp.model import compile_mdp, relevant_fits


@pytest.mark.parametrize(("parts", "seed"), [(12, 1), (16, 2), (24, 0)])
def test_holders_counted_once_bound_every_state_between_the_optimum_and_the_old_bound(parts: int, seed: int) -> None:
    task = with_probabilities(synthetic_task(parts, seed), parts)
    compiled = compile_mdp(task, relevant_fits(task))
    exact = solve_compiled_mdp(compiled, 60.0, 1e-9)
    tighter = 0
    for state, success in exact.state_success.items():
        parts_on, unusable = compiled.parts_of(state)
        compiled.holders_counted_once = True
        new = bound(compiled, parts_on, unusable, 0, 1e-9).success
        compiled.holders_counted_once = False
        old = bound(compiled, parts_on, unusable, 0, 1e-9).success
        assert success <= new + 1e-12 and new <= old + 1e-12
        tighter += new < old - 1e-12
    if parts == 24:
        assert tighter > 0  # the difference shows where holders are shared
