"""Independent components of the MDP: what couples parts, and what does not (the base)."""

from __future__ import annotations

from causalplan.comparison.families import cyclic_components, independent_components, riskiest_first_chains
from causalplan.comparison.synthetic import synthetic_task
from causalplan.pddl.task import PlanningTask
from causalplan.planners.mdp.components import goal_conjuncts
from causalplan.planners.mdp.components import independent_components as components_of
from causalplan.planners.mdp.model import compile_mdp, relevant_fits


def _components(task: PlanningTask) -> list[list[str]]:
    compiled = compile_mdp(task, relevant_fits(task))
    return [sorted({compiled.fits[index].moving_part for index in part.fits}) for part in components_of(compiled)]


def test_components_on_distinct_sockets_of_the_base_are_independent() -> None:
    found = _components(independent_components(16).task)
    assert len(found) == 16
    assert found[0] == ["c01_h", "c01_u", "c01_v", "c01_x", "c01_y"]  # a shared socket and an OR keep these together


def test_each_ring_and_each_chain_is_one_component() -> None:
    assert [len(parts) for parts in _components(cyclic_components(4).task)] == [5, 5, 5, 5]
    assert [len(parts) for parts in _components(riskiest_first_chains(3, 4).task)] == [4, 4, 4]


def test_a_tree_hanging_from_one_holder_is_one_component() -> None:
    task = synthetic_task(16, 0)
    assert len(_components(task)) == 1


def test_the_goal_splits_into_conjuncts_through_nested_ands_but_not_through_an_or() -> None:
    task = independent_components(3).task
    conjuncts = goal_conjuncts(compile_mdp(task, relevant_fits(task)))
    assert conjuncts is not None
    assert conjuncts["current 2 flows"] == frozenset({"c02_y", "c02_u"})  # the OR: one conjunct over both
    assert conjuncts["hold component 3"] == frozenset({"c03_h"})
    assert "provide power" not in conjuncts  # the base carries it: it always holds
