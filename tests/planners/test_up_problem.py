"""The axiom-free unified-planning formulation: same answers as our FD route, UP's validator agrees."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from causalplan.causal.diagnostics import Location
from causalplan.causal.model import CausalModel, Labelling
from causalplan.causal.rules import Rule, parse_rule
from causalplan.comparison.synthetic import synthetic_task
from causalplan.objects.catalog import Catalog
from causalplan.objects.model import AssemblyObject, Connector, Fit, Part, Requirement
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners.pipeline import UP_ENGINES, plan_task, planner_availability
from causalplan.planners.replay import replay
from causalplan.planners.result import PlanStatus
from causalplan.planners.up_problem import (
    build_up_problem,
    engine_problem,
    goal_structure,
    missing_program,
    solve_with_up,
    status_of_up_result,
    validate_with_up,
)
from tests.conftest import example_model

PAPER = (
    "paper/desk_lamp.yaml",
    "paper/failed_desk_lamp.yaml",
    "near/candle.yaml",
    "far/abstract_desk_lamp.yaml",
)

# Two parts that both need the base's only socket: they exclude each other.
TOY = AssemblyObject(
    id="toy", name="toy", category="electric", goal="light", description="", base="base",
    parts=(
        Part("base", "base", (Connector("socket", "socket", "E27"),)),
        Part("a", "part a", (Connector("plug", "plug", "E27"),)),
        Part("b", "part b", (Connector("plug", "plug", "E27"),)),
    ),
    fits=(
        Fit("a_in", "plug", "a", "plug", "base", "socket", 1.0),
        Fit("b_in", "plug", "b", "plug", "base", "socket", 1.0),
    ),
    mechanism=(Requirement(("a_in",), "part a is plugged in"),),
    mechanism_explanation="Only part a makes light.",
)  # fmt: skip


def _rules(*texts: str) -> tuple[Rule, ...]:
    rules = []
    for index, text in enumerate(texts, start=1):
        rule, _ = parse_rule(text, index, Location())
        assert rule is not None
        rules.append(rule)
    return tuple(rules)


def _toy_task(functions: dict[str, tuple[str, ...]], *rules: str) -> PlanningTask:
    return build_task(CausalModel(Labelling("toy", functions), "light", _rules(*rules)), TOY)


def _paper_task(relative: str, catalog: Catalog) -> PlanningTask:
    model = example_model(relative, catalog)
    return build_task(model, catalog.get(model.object_id))


def _functions_in(formula: Any) -> set[str]:
    if formula[0] == "fn":
        return {formula[1]}
    if formula[0] in ("and", "or"):
        return set().union(*(_functions_in(part) for part in formula[1]))
    return set()


def test_the_desk_lamp_becomes_one_grounded_action_per_fit(catalog: Catalog) -> None:
    task = _paper_task("paper/failed_desk_lamp.yaml", catalog)
    problem, actions = build_up_problem(task)
    assert sorted(actions.values()) == [
        ("clip", ("shade", "base_with_cables", "shade_onto_ring")),
        ("screw", ("light_bulb", "base_with_cables", "bulb_into_socket")),
    ]
    assert sorted(action.name for action in problem.actions) == sorted(actions)
    assert sorted(fluent.name for fluent in problem.fluents) == ["active", "available", "detached", "in_assembly"]
    shade = problem.action("clip__shade__base_with_cables__shade_onto_ring")
    # The shade covers the socket: clipping it makes both fits unavailable, and activates its function.
    assert sorted(str(effect) for effect in shade.effects) == [
        "active(node_diffuse_light) := true",
        "available(fit_bulb_into_socket) := false",
        "available(fit_shade_onto_ring) := false",
        "detached(part_shade) := false",
        "in_assembly(part_shade) := true",
    ]
    initial = {str(fluent): str(value) for fluent, value in problem.explicit_initial_values.items()}
    assert initial["in_assembly(part_base_with_cables)"] == "true"
    assert initial["active(node_provide_electricity)"] == "true"
    assert len(problem.goals) == 1


def test_the_goal_is_the_causal_graph_unrolled(catalog: Catalog) -> None:
    task = _paper_task("paper/desk_lamp.yaml", catalog)
    assert goal_structure(task) == (
        "and",
        [("and", [("fn", "close the circuit"), ("fn", "provide electricity")]), ("fn", "turn electricity into light")],
    )
    # Rules with the same effect are alternatives.
    either = _toy_task({"a": ("fa",), "b": ("fb",)}, "fa CAUSES glow", "fb CAUSES glow", "glow CAUSES light")
    assert goal_structure(either) == ("or", [("fn", "fa"), ("fn", "fb")])


def test_cycles_and_missing_functions_contribute_false() -> None:
    cyclic = _toy_task({"a": ("fa",), "b": ("fb",)}, "x CAUSES y", "y CAUSES x", "x AND fa CAUSES light", "fb CAUSES x")
    assert goal_structure(cyclic) == ("and", [("fn", "fa"), ("fn", "fb")])
    assert goal_structure(_toy_task({"a": ("fa",)}, "fa AND nowhere CAUSES light")) == ("false",)
    assert goal_structure(_toy_task({"base": ("power",)}, "power CAUSES light")) == ("fn", "power")


def _depths(obj: AssemblyObject) -> dict[str, int]:
    """Return each part's depth in the tree of first (primary) fits."""
    depth = {obj.base: 0}
    for fit in obj.fits:
        if fit.moving_part not in depth:
            depth[fit.moving_part] = depth[fit.fixed_part] + 1
    return depth


def test_a_synthetic_goal_has_an_or_and_reaches_the_deepest_part() -> None:
    task = synthetic_task(40)
    formula = goal_structure(task)
    assert "('or'," in repr(formula)
    depth = _depths(task.obj)
    used = {part for key in _functions_in(formula) for part in task.carriers()[key]}
    assert task.obj.base in used
    assert max(depth[part] for part in used) == max(depth.values()) >= 4
    _problem, actions = build_up_problem(task)
    assert len(actions) == len(task.obj.fits)


@pytest.mark.parametrize("relative", PAPER)
def test_up_optimal_and_our_optimal_plans_have_the_same_length(relative: str, catalog: Catalog) -> None:
    task = _paper_task(relative, catalog)
    ours = plan_task(task, "fd-opt")
    theirs = solve_with_up(task, "fast-downward-opt", 30)
    assert ours.status is PlanStatus.SOLVED and theirs.status is PlanStatus.SOLVED, theirs.message
    assert len(theirs.actions) == len(ours.steps)
    checked = replay(task, theirs.actions)
    assert checked.executable and checked.valid_under_model


@pytest.mark.parametrize("relative", PAPER)
def test_the_up_validator_accepts_our_plan_and_rejects_it_with_a_step_removed(relative: str, catalog: Catalog) -> None:
    task = _paper_task(relative, catalog)
    result = plan_task(task, "fd")
    assert result.status is PlanStatus.SOLVED
    actions = tuple((step.action, (*step.args, step.fit)) for step in result.steps)
    assert validate_with_up(task, actions)
    for missing in range(len(actions)):
        assert not validate_with_up(task, actions[:missing] + actions[missing + 1 :])


def test_the_up_validator_rejects_wrong_order_and_unknown_steps(catalog: Catalog) -> None:
    task = _paper_task("paper/failed_desk_lamp.yaml", catalog)
    bulb = ("screw", ("light_bulb", "base_with_cables", "bulb_into_socket"))
    shade = ("clip", ("shade", "base_with_cables", "shade_onto_ring"))
    assert validate_with_up(task, (bulb, shade))
    assert not validate_with_up(task, (shade, bulb))  # the shade covers the socket
    assert not validate_with_up(task, (bulb, bulb))
    assert not validate_with_up(task, (bulb, ("clip", ("shade", "light_bulb", "shade_onto_ring"))))


def test_up_statuses_map_to_ours() -> None:
    assert status_of_up_result("SOLVED_SATISFICING") is PlanStatus.SOLVED
    assert status_of_up_result("SOLVED_OPTIMALLY") is PlanStatus.SOLVED
    assert status_of_up_result("UNSOLVABLE_PROVEN") is PlanStatus.UNSOLVABLE
    assert status_of_up_result("UNSOLVABLE_INCOMPLETELY") is PlanStatus.UNSOLVABLE
    assert status_of_up_result("TIMEOUT") is PlanStatus.TIMEOUT
    assert status_of_up_result("MEMOUT") is PlanStatus.OUT_OF_MEMORY
    assert status_of_up_result("INTERNAL_ERROR") is PlanStatus.ERROR
    assert status_of_up_result("UNSUPPORTED_PROBLEM") is PlanStatus.ERROR


def test_exclusive_parts_are_unsolvable_through_up_as_through_ours() -> None:
    task = _toy_task({"a": ("fa",), "b": ("fb",)}, "fa AND fb CAUSES light")
    assert solve_with_up(task, "fast-downward", 30).status is PlanStatus.UNSOLVABLE
    assert plan_task(task, "fd").status is PlanStatus.UNSOLVABLE
    # A goal no part can produce is a well-formed, unsolvable UP problem (PDDL has no "false").
    impossible = _toy_task({"a": ("fa",)}, "fa AND nowhere CAUSES light")
    assert solve_with_up(impossible, "fast-downward-opt", 30).status is PlanStatus.UNSOLVABLE


def test_a_goal_that_already_holds_needs_the_empty_plan() -> None:
    task = _toy_task({"base": ("power",), "a": ("fa",)}, "power CAUSES light", "fa CAUSES light")
    outcome = solve_with_up(task, "fast-downward", 30)
    assert outcome.status is PlanStatus.SOLVED and outcome.actions == ()
    assert validate_with_up(task, ())


def test_engine_failures_are_outcomes_not_exceptions(catalog: Catalog) -> None:
    task = _paper_task("paper/desk_lamp.yaml", catalog)
    missing = solve_with_up(task, "no-such-engine", 5)
    assert missing.status is PlanStatus.ERROR and "no-such-engine" in missing.message


@pytest.mark.parametrize("engine", UP_ENGINES)
def test_every_installed_engine_solves_a_task_with_a_disjunctive_goal(engine: str) -> None:
    # Synthetic tasks have an OR in their goal; pyperplan gets it compiled away by UP itself.
    missing = missing_program(engine)
    if missing is not None:  # ENHSP runs Java, which no wheel ships: it is then reported unavailable
        pytest.skip(missing)
    task = synthetic_task(8, seed=1)
    outcome = solve_with_up(task, engine, 60)
    assert outcome.status is PlanStatus.SOLVED, outcome.message
    assert replay(task, outcome.actions).valid_under_model
    assert validate_with_up(task, outcome.actions)


def test_engine_availability_is_reported() -> None:
    assert engine_problem("tamer") is None
    problem = engine_problem("no-such-engine")
    assert problem is not None and "no-such-engine" in problem


def test_enhsp_without_java_is_unavailable_saying_why_and_its_plan_is_an_error_saying_so(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # an empty folder: no 'java' on PATH
    availability = planner_availability()
    for engine in ("enhsp", "enhsp-opt"):
        why = availability[f"up:{engine}"]
        assert why is not None and "'java'" in why and "not on PATH" in why
    assert availability["up:tamer"] is None  # a pure-Python engine needs nothing from PATH
    outcome = solve_with_up(synthetic_task(4, seed=0), "enhsp", 30)
    assert outcome.status is PlanStatus.ERROR and outcome.message == availability["up:enhsp"]


def test_a_synthetic_plan_through_up_replays_and_validates() -> None:
    task = synthetic_task(40, seed=3)
    outcome = solve_with_up(task, "fast-downward", 60)
    assert outcome.status is PlanStatus.SOLVED, outcome.message
    checked = replay(task, outcome.actions)
    assert checked.executable and checked.valid_under_model and checked.valid_under_true_mechanism
    assert validate_with_up(task, outcome.actions)
    ours = plan_task(task, "fd")
    assert validate_with_up(task, tuple((step.action, (*step.args, step.fit)) for step in ours.steps))


def test_fast_downward_through_up_never_writes_in_the_working_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Two runs from one directory (pytest-xdist's workers, a server's workers) shared FD's output.sas.
    monkeypatch.chdir(tmp_path)
    (tmp_path / "output.sas").mkdir()  # FD cannot write its translated task here
    task = _toy_task({"base": ("power",), "a": ("fa",)}, "power AND fa CAUSES light")
    for engine in ("fast-downward", "fast-downward-opt"):
        outcome = solve_with_up(task, engine, 30)
        assert outcome.status is PlanStatus.SOLVED and len(outcome.actions) == 1, outcome.message
    assert [path.name for path in tmp_path.iterdir()] == ["output.sas"]
