"""The RDDL export, checked by a simulator nobody here wrote: pyRDDLGym rolls out our policy."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pyRDDLGym
import pytest
from click.testing import CliRunner

from causalplan.cli import app
from causalplan.comparison.families import independent_components, uncertain_tree, with_probabilities
from causalplan.comparison.synthetic import synthetic_task
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners.mdp import MdpSolution, Optimality, solve_mdp_search
from causalplan.planners.mdp.model import compile_mdp
from causalplan.planners.mdp.objective import solve_for
from causalplan.planners.mdp.search import decide
from causalplan.planners.rddl import RddlTask, _names, export_rddl
from tests.conftest import EXAMPLES, example_mapping, example_model

EPISODES = 2000
Z_99 = 2.5758  # two-sided 99% normal quantile


def _simulated_success(
    exported: RddlTask, task: PlanningTask, solution: MdpSolution, folder: Path, episodes: int = EPISODES
) -> float:
    """Return the share of pyRDDLGym episodes, following our policy, in which the simulator's ``lit`` holds."""
    (folder / "domain.rddl").write_text(exported.domain, encoding="utf-8")
    (folder / "instance.rddl").write_text(exported.instance, encoding="utf-8")
    env = pyRDDLGym.make(str(folder / "domain.rddl"), str(folder / "instance.rddl"))
    compiled = compile_mdp(task, solution.fits)
    successes = 0
    for episode in range(episodes):
        observation, _ = env.reset(seed=episode)
        made = failed = 0
        while (index := decide(compiled, solution, (made, failed))) >= 0:
            fit = solution.fits[index]
            observation, *_ = env.step({exported.action(fit.id): True})
            if observation[exported.attached(fit.moving_part)]:  # the simulator drew the outcome
                made |= 1 << index
            else:
                failed |= 1 << index
        observation, *_ = env.step({})  # `lit` follows the goal one step later
        successes += bool(observation["lit"])
    env.close()
    return successes / episodes


def _interval(probability: float, episodes: int = EPISODES) -> tuple[float, float]:
    half = Z_99 * math.sqrt(probability * (1 - probability) / episodes) + 0.5 / episodes
    return probability - half, probability + half


def _paper_task(model_file: str, mapping_file: str | None, catalog: Catalog) -> PlanningTask:
    model = example_model(model_file, catalog)
    mapping = example_mapping(mapping_file, catalog) if mapping_file else None
    return build_task(model, catalog.get(mapping.object_id if mapping else model.object_id), mapping)


PAPER_TASKS = [
    ("paper/desk_lamp.yaml", None),
    ("paper/desk_lamp.yaml", "paper/flashlight_mapping.yaml"),
    ("near/candle.yaml", None),
    ("near/candle.yaml", "near/kerosene_lamp_mapping.yaml"),
]


@pytest.mark.slow
@pytest.mark.parametrize(("model_file", "mapping_file"), PAPER_TASKS)
def test_pyrddlgym_agrees_with_our_success_probability_on_the_paper_objects(
    model_file: str, mapping_file: str | None, catalog: Catalog, tmp_path: Path
) -> None:
    task = with_probabilities(_paper_task(model_file, mapping_file, catalog), 3, low=0.5)
    solution = solve_mdp_search(task)
    assert solution.success_probability is not None
    low, high = _interval(solution.success_probability)
    assert low <= _simulated_success(export_rddl(task), task, solution, tmp_path) <= high


@pytest.mark.slow
def test_pyrddlgym_agrees_on_a_synthetic_object_with_several_uncertain_fits(tmp_path: Path) -> None:
    task = with_probabilities(synthetic_task(9, 0), 0, low=0.6)
    assert sum(fit.probability < 1 for fit in task.obj.fits) >= 4
    solution = solve_mdp_search(task)
    assert solution.success_probability is not None and 0.1 < solution.success_probability < 0.9
    assert len(solution.policy) > 3  # a closed-loop policy: it reacts to failures
    low, high = _interval(solution.success_probability)
    assert low <= _simulated_success(export_rddl(task), task, solution, tmp_path) <= high


@pytest.mark.slow
def test_a_wrong_probability_is_caught(tmp_path: Path) -> None:
    task = with_probabilities(synthetic_task(9, 0), 0, low=0.6)
    solution = solve_mdp_search(task)
    assert solution.success_probability is not None and solution.actions
    first = solution.actions[0][1][2]  # the first fit the policy attempts: lower it in what we plan with
    wrong_fits = tuple(
        dataclasses.replace(fit, probability=fit.probability * 0.6) if fit.id == first else fit for fit in task.obj.fits
    )
    wrong = dataclasses.replace(task, obj=dataclasses.replace(task.obj, fits=wrong_fits))
    wrong_solution = solve_mdp_search(wrong)
    assert wrong_solution.success_probability is not None
    low, high = _interval(wrong_solution.success_probability)
    # The simulator runs the true object: the wrong figure is outside the interval.
    simulated = _simulated_success(export_rddl(task), wrong, wrong_solution, tmp_path)
    assert not low <= simulated <= high


def test_the_export_names_objects_and_never_writes_labels(catalog: Catalog) -> None:
    task = _paper_task("paper/desk_lamp.yaml", None, catalog)
    exported = export_rddl(task)
    assert exported.action("bulb_into_socket") == "attempt___bulb_into_socket"
    assert "P(bulb_into_socket) = 1.0;" in exported.instance
    assert "init-state { attached(base_with_cables) = true; };" in exported.instance
    for label in task.node_labels().values():
        assert label not in exported.domain


def test_export_rddl_writes_a_domain_and_an_instance(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["export-rddl", str(EXAMPLES / "paper/desk_lamp.yaml"), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "domain.rddl").read_text().startswith("domain causalplan_desk_lamp {")
    assert "non-fluents nf_causalplan_desk_lamp" in (tmp_path / "instance.rddl").read_text()


def test_made_up_names_never_take_a_kept_id() -> None:
    names = _names(("if", "part_1", "x-y", "Part_2"), "part")
    assert names["part_1"] == "part_1" and names["Part_2"] == "Part_2"
    assert len({name.lower() for name in names.values()}) == 4
    assert names["if"] == "part_3" and names["x-y"] == "part_4"


def _more_reliable(task: PlanningTask, factor: float) -> PlanningTask:
    """Return the task with every failure chance divided by ``factor``."""
    fits = tuple(dataclasses.replace(fit, probability=1 - (1 - fit.probability) / factor) for fit in task.obj.fits)
    return dataclasses.replace(task, obj=dataclasses.replace(task.obj, fits=fits))


@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.parametrize(("kind", "episodes"), [("components", 200), ("tree", EPISODES)])
def test_pyrddlgym_agrees_with_the_80_part_policy(kind: str, episodes: int, tmp_path: Path) -> None:
    # Sixteen independent components (the composed policy) and a tree with 15 uncertain fits.
    task = _more_reliable(independent_components(16).task, 6) if kind == "components" else uncertain_tree(80, 15, 0)
    assert len(task.obj.parts) >= 80
    solution = solve_for(task, 30.0)
    assert solution.optimality is Optimality.OPTIMAL and solution.success_probability is not None
    assert 0.05 < solution.success_probability < 0.95
    # pyRDDLGym takes about a second for an episode of the components' 60-odd attempts: fewer episodes there,
    # a wider interval, still 99%.
    low, high = _interval(solution.success_probability, episodes)
    assert low <= _simulated_success(export_rddl(task), task, solution, tmp_path, episodes) <= high
