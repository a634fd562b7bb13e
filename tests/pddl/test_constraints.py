"""A question's constraints compiled into the problem file: Fast Downward and VAL honour them, replay checks them."""

from __future__ import annotations

from dataclasses import replace

import pytest

from causalplan.objects.catalog import Catalog
from causalplan.pddl.canonical import canonical_pddl
from causalplan.pddl.constraints import InvalidConstraintError, PlanConstraints
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.pddl.writer import compile_task
from causalplan.planners.pipeline import UnknownPlannerError, plan_task
from causalplan.planners.replay import replay
from causalplan.planners.result import PlanStatus
from tests.conftest import example_model

SHADE_FIRST = PlanConstraints(orderings=frozenset({("shade", "light_bulb")}))


def _task(catalog: Catalog, model: str = "paper/desk_lamp.yaml") -> PlanningTask:
    return build_task(example_model(model, catalog), catalog.get("desk_lamp"))


def test_no_constraints_write_the_same_problem(catalog: Catalog) -> None:
    task = _task(catalog)
    plain = compile_task(task).problem
    assert compile_task(replace(task, constraints=PlanConstraints())).problem == plain
    # Without constraints: the model's goal alone, and every fit available.
    assert "(:goal (n-light))" in plain
    assert plain.count("(available ") == len(task.obj.fits)


def test_constraints_go_into_the_problem_only(catalog: Catalog) -> None:
    task = _task(catalog)
    constrained = replace(
        task,
        constraints=PlanConstraints(
            required_parts=frozenset({"shade"}), forbidden_fits=frozenset({"bulb_into_socket"}), orderings=frozenset()
        ),
    )
    plain, compiled = compile_task(task), compile_task(constrained)
    assert compiled.domain == plain.domain
    assert "(:goal (and (n-light) (in-assembly shade)))" in compiled.problem
    assert "(available bulb_into_socket)" not in compiled.problem
    canonical = canonical_pddl(constrained)
    assert canonical is not None and "(:goal (and (goal) (in-assembly shade)))" in canonical.problem


def test_an_ordering_adds_exclusions(catalog: Catalog) -> None:
    problem = compile_task(replace(_task(catalog), constraints=SHADE_FIRST)).problem
    # Once the bulb is in, the shade can no longer go on: so the shade goes first.
    assert "(excludes bulb_into_socket shade_onto_ring)" in problem
    assert "(in-assembly light_bulb) (in-assembly shade)" in problem


def test_an_impossible_order_is_unsolvable(catalog: Catalog) -> None:
    result = plan_task(replace(_task(catalog), constraints=SHADE_FIRST), "fd-opt")
    assert result.status is PlanStatus.UNSOLVABLE


def test_a_required_part_is_attached_and_validated(catalog: Catalog) -> None:
    task = replace(_task(catalog), constraints=PlanConstraints(required_parts=frozenset({"shade"})))
    result = plan_task(task, "fd-opt", val=True)
    assert [step.fit for step in result.steps] == ["bulb_into_socket", "shade_onto_ring"]
    assert result.validated_by == {"replay": "valid", "val": "valid"}


def test_replay_checks_the_constraints(catalog: Catalog) -> None:
    task = replace(_task(catalog), constraints=PlanConstraints(required_parts=frozenset({"shade"})))
    bulb_only = (("screw", ("light_bulb", "base_with_cables", "bulb_into_socket")),)
    assert replay(task, bulb_only).valid_under_model is False
    assert replay(_task(catalog), bulb_only).valid_under_model is True


def test_unknown_ids_are_refused(catalog: Catalog) -> None:
    task = replace(_task(catalog), constraints=PlanConstraints(required_parts=frozenset({"x) (:action evil"})))
    with pytest.raises(InvalidConstraintError) as raised:
        compile_task(task)
    assert raised.value.code == "invalid_constraint"


def test_only_fast_downward_plans_with_constraints(catalog: Catalog) -> None:
    with pytest.raises(UnknownPlannerError):
        plan_task(replace(_task(catalog), constraints=SHADE_FIRST), "mdp")
