"""The MDP at 80 parts and more: products of independent components, against closed forms and mdp-exact."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.comparison.families import (
    KnownOptimum,
    cyclic_components,
    documents,
    independent_components,
    riskiest_first_chains,
    uncertain_tree,
)
from causalplan.pddl.task import PlanningTask
from causalplan.planners.fd.solve import DEFAULT_TIME_LIMIT
from causalplan.planners.mdp import Optimality
from causalplan.planners.mdp.composed import sidney_modules
from causalplan.planners.mdp.model import relevant_fits
from causalplan.planners.mdp.objective import solve_for
from causalplan.planners.result import PlanStatus


def _relevant_parts(task: PlanningTask) -> int:
    return len({part for fit in relevant_fits(task) for part in (fit.moving_part, fit.fixed_part)} - {task.obj.base})


@pytest.mark.parametrize(
    "family",
    [independent_components(16), cyclic_components(16, 1), riskiest_first_chains(16, 5), riskiest_first_chains(20, 5)],
    ids=lambda family: family.task.obj.id,
)
def test_at_80_parts_and_more_the_answer_is_the_closed_form_optimum(family: KnownOptimum) -> None:
    assert _relevant_parts(family.task) >= 80
    solution = solve_for(family.task, DEFAULT_TIME_LIMIT)
    assert solution.status is PlanStatus.SOLVED and solution.optimality is Optimality.OPTIMAL, solution.message
    assert solution.success_probability is not None
    assert abs(solution.success_probability - family.success_probability) <= 1e-9 * family.success_probability
    if family.expected_attempts is not None:  # chains: the ratio rule interleaves them, as Sidney's decomposition
        assert solution.expected_actions == pytest.approx(family.expected_attempts, abs=1e-9)


@pytest.mark.parametrize(
    "family", [independent_components(2, 5), cyclic_components(2, 3), riskiest_first_chains(3, 3, 1)]
)
def test_mdp_exact_agrees_where_it_runs(family: KnownOptimum) -> None:
    exact = solve_for(family.task, 60.0, exact=True)
    solution = solve_for(family.task, 60.0)
    assert exact.status is solution.status is PlanStatus.SOLVED
    assert exact.success_probability == pytest.approx(family.success_probability, abs=1e-12)
    assert solution.success_probability == pytest.approx(family.success_probability, abs=1e-12)
    assert exact.expected_actions is not None and solution.expected_actions is not None
    assert solution.expected_actions >= exact.expected_actions - 1e-9


def test_sidney_splits_a_chain_where_the_ratio_peaks() -> None:
    # A sure test before a risky one: together (1 - 0.5) / 2 beats the sure test alone (0 / 1).
    assert sidney_modules([1.0, 0.5]) == [(2, 0.5, 2.0)]
    # Risk increasing along the chain: each test is its own segment, riskiest ratio first.
    assert [end for end, _, _ in sidney_modules([0.5, 0.9])] == [1, 2]
    # Risk decreasing: the first alone has the highest ratio, then the rest.
    segments = sidney_modules([0.9, 0.5])
    assert [end for end, _, _ in segments] == [2]
    assert segments[0][1:] == pytest.approx((0.45, 1.9))


@pytest.mark.parametrize("kind", ["tree", "components"])
def test_causalplan_plan_answers_optimal_on_80_part_objects_in_a_third_of_the_default_limit(
    kind: str, tmp_path: Path
) -> None:
    task = uncertain_tree(80, 15, 0) if kind == "tree" else independent_components(16).task
    assert len(task.obj.parts) >= 80
    object_document, model_document = documents(task)
    (tmp_path / "catalog").mkdir()
    (tmp_path / "catalog" / "object.yaml").write_text(yaml.safe_dump(object_document), encoding="utf-8")
    (tmp_path / "model.yaml").write_text(yaml.safe_dump(model_document), encoding="utf-8")
    limit = DEFAULT_TIME_LIMIT / 3
    result = CliRunner().invoke(
        app,
        [
            "plan",
            str(tmp_path / "model.yaml"),
            "--catalog",
            str(tmp_path / "catalog"),
            "--planner",
            "mdp",
            "--time-limit",
            str(limit),
            "--json",
        ],
    )
    assert result.exit_code == 0, result.output
    answer = json.loads(result.output)
    assert answer["status"] == "solved" and answer["optimality"] == "optimal", answer["message"]
    low, high = answer["success_probability_bounds"]
    assert math.isclose(low, high) and answer["success_probability"] > 0.0
    if kind == "components":
        expected = independent_components(16).success_probability
        assert answer["success_probability"] == pytest.approx(expected, abs=5e-7)  # the JSON keeps 6 places
