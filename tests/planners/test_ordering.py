"""A plan's steps put in the order the true mechanism needs, without a step added or dropped."""

from __future__ import annotations

from dataclasses import replace

from causalplan.objects.catalog import Catalog
from causalplan.pddl.constraints import PlanConstraints
from causalplan.planners.ordering import mechanism_order
from tests.objects.test_mechanism_order import reference_task

WICK = ("insert", ("wick", "lamp_bowl", "wick_into_spout"))
LIGHT = ("ignite", ("match", "wick", "match_lights_wick"))
OIL = ("insert", ("oil_bottle", "lamp_bowl", "bottle_into_filling_hole"))


def test_the_wick_is_lit_after_the_oil_and_a_plan_in_order_keeps_the_planners_order(catalog: Catalog) -> None:
    task = reference_task(catalog.get("oil_lamp"), catalog)
    # the oil first, then the wick, as the mechanism lists them, and the flame last
    assert mechanism_order(task, (WICK, LIGHT, OIL)) == (OIL, WICK, LIGHT)
    assert mechanism_order(task, (WICK, OIL, LIGHT)) == (WICK, OIL, LIGHT)  # already in order: the planner's


def test_a_step_the_plan_does_not_have_is_not_waited_for(catalog: Catalog) -> None:
    task = reference_task(catalog.get("oil_lamp"), catalog)
    assert mechanism_order(task, (WICK, LIGHT)) == (WICK, LIGHT)  # no oil in the plan: nothing to wait for


def test_when_the_constraints_allow_no_such_order_the_planners_order_is_kept(catalog: Catalog) -> None:
    task = reference_task(catalog.get("oil_lamp"), catalog)
    lit_first = replace(task, constraints=PlanConstraints(orderings=frozenset({("match", "oil_bottle")})))
    assert mechanism_order(lit_first, (WICK, LIGHT, OIL)) == (WICK, LIGHT, OIL)
