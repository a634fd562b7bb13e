"""The PDDL writer: hostile labels cannot change the PDDL's meaning; output parses and plans."""

from __future__ import annotations

from pathlib import Path

from pddl import parse_domain, parse_problem
from pddl.core import Domain, Problem

from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel, read_model
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task
from causalplan.pddl.writer import compile_task
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanStatus

EVIL = "x) (:action evil :parameters () :precondition () :effect (n-light)) (:derived (n-light) (and)"


def _model(functions: dict[str, list[str]], rules: list[str], catalog: Catalog, goal: str = "light") -> CausalModel:
    model, problems = read_model(
        {"object": "desk_lamp", "goal": goal, "functions": functions, "rules": rules}, SourceMap()
    )
    assert model is not None and not [p for p in problems if p.severity.value == "error"]
    return model


def _parse(tmp_path: Path, domain: str, problem: str) -> tuple[Domain, Problem]:
    (tmp_path / "domain.pddl").write_text(domain)
    (tmp_path / "problem.pddl").write_text(problem)
    return parse_domain(tmp_path / "domain.pddl"), parse_problem(tmp_path / "problem.pddl")


def test_a_hostile_label_cannot_add_actions_or_axioms(catalog: Catalog, tmp_path: Path) -> None:
    model = _model(
        {"base_with_cables": [EVIL], "light_bulb": ["turn electricity into light"]},
        [f"{EVIL} AND turn electricity into light CAUSES light"],
        catalog,
    )
    compiled = compile_task(build_task(model, catalog.get("desk_lamp")))
    domain, _problem = _parse(tmp_path, compiled.domain, compiled.problem)
    assert sorted(action.name for action in domain.actions) == ["clip", "screw"]
    assert len(domain.derived_predicates) == 3  # two function carriers and one rule
    result = plan_task(build_task(model, catalog.get("desk_lamp")), "fd")
    assert result.status is PlanStatus.SOLVED
    assert [step.fit for step in result.steps] == ["bulb_into_socket"]


def test_a_hostile_goal_label_stays_one_predicate(catalog: Catalog, tmp_path: Path) -> None:
    model = _model(
        {"base_with_cables": ["power"], "light_bulb": ["glow"]}, [f"power AND glow CAUSES {EVIL}"], catalog, goal=EVIL
    )
    compiled = compile_task(build_task(model, catalog.get("desk_lamp")))
    _domain, problem = _parse(tmp_path, compiled.domain, compiled.problem)
    assert str(problem.goal) == f"({compiled.node_names[model.goal_key]})"


def test_labels_colliding_after_sanitising_stay_distinct_nodes(catalog: Catalog) -> None:
    # 'power!' and 'power?' both sanitise to 'power'; only one of them is carried by the bulb.
    model = _model(
        {"base_with_cables": ["power!"], "light_bulb": ["power?"], "shade": ["glow"]},
        ["power! AND glow CAUSES light"],
        catalog,
    )
    compiled = compile_task(build_task(model, catalog.get("desk_lamp")))
    assert compiled.node_names["power!"] != compiled.node_names["power?"]
    result = plan_task(build_task(model, catalog.get("desk_lamp")), "fd-opt")
    # If the two labels had merged, screwing in the bulb alone would do; the shade is needed.
    assert [step.fit for step in result.steps] == ["shade_onto_ring"]


def test_compilation_is_pure_and_deterministic(catalog: Catalog) -> None:
    model = _model({"base_with_cables": ["b", "a"], "light_bulb": ["c"]}, ["a AND b AND c CAUSES light"], catalog)
    first = compile_task(build_task(model, catalog.get("desk_lamp")))
    second = compile_task(build_task(model, catalog.get("desk_lamp")))
    assert first == second
    assert "(:derived (n-light) (and (n-a) (n-b) (n-c)))" in first.domain


def test_alternative_rules_become_alternative_clauses(catalog: Catalog) -> None:
    model = _model(
        {"base_with_cables": ["mains"], "light_bulb": ["glow"], "shade": ["reflect"]},
        ["mains AND glow CAUSES light", "reflect CAUSES light"],
        catalog,
    )
    domain = compile_task(build_task(model, catalog.get("desk_lamp"))).domain
    assert domain.count("(:derived (n-light)") == 2
    result = plan_task(build_task(model, catalog.get("desk_lamp")), "fd-opt")
    assert len(result.steps) == 1
