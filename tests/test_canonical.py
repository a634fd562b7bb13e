"""The canonical form: the goal as minimal part sets, equal for equal problems, same answers."""

from __future__ import annotations

import pytest

from causalplan.causal.documents import SourceMap
from causalplan.causal.model import read_model
from causalplan.objects.catalog import Catalog
from causalplan.pddl import canonical
from causalplan.pddl.canonical import MAX_MINIMAL_SETS, canonical_pddl, minimal_part_sets
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.pddl.writer import compile_task
from causalplan.planners import fast_downward
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanStatus
from causalplan.planners.synthetic import synthetic_object, synthetic_task
from tests.conftest import example_mapping, example_model


def _task(functions: dict[str, list[str]], rules: list[str], catalog: Catalog) -> PlanningTask:
    model, _ = read_model({"object": "desk_lamp", "functions": functions, "rules": rules}, SourceMap())
    assert model is not None
    return build_task(model, catalog.get("desk_lamp"))


def test_minimal_sets_of_the_paper_models(catalog: Catalog) -> None:
    lamp = build_task(example_model("paper/failed_desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    assert minimal_part_sets(lamp) == {frozenset({"light_bulb", "shade"})}  # the base is always there
    torch = build_task(
        example_model("paper/desk_lamp.yaml", catalog),
        catalog.get("flashlight"),
        example_mapping("paper/flashlight_mapping.yaml", catalog),
    )
    assert minimal_part_sets(torch) == {frozenset({"batteries", "head"})}


def test_alternatives_give_several_sets_and_supersets_are_dropped(catalog: Catalog) -> None:
    task = _task(
        {"light_bulb": ["glow"], "shade": ["reflect"]},
        ["glow CAUSES light", "glow AND reflect CAUSES light", "reflect CAUSES shine", "shine CAUSES light"],
        catalog,
    )
    assert minimal_part_sets(task) == {frozenset({"light_bulb"}), frozenset({"shade"})}


def test_labels_and_unused_functions_do_not_change_the_canonical_form(catalog: Catalog) -> None:
    plain = _task({"light_bulb": ["glow"]}, ["glow CAUSES light"], catalog)
    reworded = _task(
        {"light_bulb": ["Turn Electricity Into Light"], "shade": ["hold things together"]},
        ["turn electricity into light CAUSES photons", "photons CAUSES light"],
        catalog,
    )
    assert canonical_pddl(plain) == canonical_pddl(reworded)
    assert compile_task(plain) != compile_task(reworded)


def test_cycles_contribute_nothing_and_too_many_sets_give_none(catalog: Catalog) -> None:
    task = _task({"light_bulb": ["glow"]}, ["glow AND heat CAUSES light", "light CAUSES heat"], catalog)
    assert minimal_part_sets(task) == frozenset()
    many = synthetic_task(40, seed=0)
    assert minimal_part_sets(many) is not None
    assert MAX_MINIMAL_SETS >= 2
    assert minimal_part_sets(_choices(6)) is not None  # 2**6 = 64 sets: at the limit
    assert minimal_part_sets(_choices(7)) is None  # 2**7 = 128 sets: too many
    assert canonical_pddl(_choices(7)) is None


def _choices(count: int) -> PlanningTask:
    """Return a task whose goal needs one of two parts for each of ``count`` causes: 2**count minimal sets."""
    obj = synthetic_object(2 * count + 1, seed=0)
    parts = [part for part in obj.part_ids if part != obj.base]
    functions = {part: [f"f{index}"] for index, part in enumerate(parts)}
    rules = [f"f{index} CAUSES c{index // 2}" for index in range(len(parts))]
    rules.append(" AND ".join(f"c{cause}" for cause in range(count)) + " CAUSES light")
    model, problems = read_model({"object": obj.id, "functions": functions, "rules": rules}, SourceMap())
    assert model is not None and problems == []
    return build_task(model, obj)


def test_an_effect_shared_by_many_rules_is_worked_out_once(catalog: Catalog, monkeypatch: pytest.MonkeyPatch) -> None:
    # A chain of diamonds: each level's two effects both need the level below, so a node is
    # reached along 2**depth paths; planning must not walk them all.
    depth = 16
    rules = [f"x{depth} CAUSES light"]
    for level in range(depth):
        rules += [
            f"x{level} CAUSES a{level}",
            f"x{level} CAUSES b{level}",
            f"a{level} AND b{level} CAUSES x{level + 1}",
        ]
    task = _task({"light_bulb": ["x0"]}, rules, catalog)
    calls = 0
    minimize = canonical._minimize

    def counted(sets: set[frozenset[str]]) -> set[frozenset[str]]:
        nonlocal calls
        calls += 1
        return minimize(sets)

    monkeypatch.setattr(canonical, "_minimize", counted)
    assert minimal_part_sets(task) == {frozenset({"light_bulb"})}
    assert calls < 10 * depth


@pytest.mark.parametrize("seed", range(6))
def test_canonical_and_readable_forms_give_the_same_answers(seed: int) -> None:
    task = synthetic_task(8 + 3 * seed, seed)
    readable, canonical = compile_task(task), canonical_pddl(task)
    assert canonical is not None
    config = fast_downward.CONFIGS["fd-opt"]
    first = fast_downward.solve(readable.domain, readable.problem, config)
    second = fast_downward.solve(canonical.domain, canonical.problem, config)
    assert first.status is second.status is PlanStatus.SOLVED
    assert len(first.actions) == len(second.actions)


def test_a_repeated_solve_comes_from_the_cache_with_the_same_plan(catalog: Catalog) -> None:
    task = build_task(example_model("near/candle.yaml", catalog), catalog.get("candle"))
    first, again = plan_task(task, "fd"), plan_task(task, "fd")
    assert first.steps == again.steps and again.status is PlanStatus.SOLVED
    assert "translate" in first.timing and "cached" in again.timing
    # an isomorphic model with other words shares the solve
    other = build_task(example_model("far/abstract_desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    lamp = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    assert plan_task(lamp, "fd").steps == plan_task(other, "fd").steps
    assert "cached" in plan_task(other, "fd").timing


def test_timeouts_are_not_cached() -> None:
    big = compile_task(synthetic_task(320, seed=0))
    config = fast_downward.CONFIGS["fd"]
    assert fast_downward.solve(big.domain, big.problem, config, time_limit=0.05).status is PlanStatus.TIMEOUT
    assert fast_downward.solve(big.domain, big.problem, config, time_limit=60).status is PlanStatus.SOLVED
