"""The canonical form: the goal as minimal part sets, equal for equal problems, same answers."""

from __future__ import annotations

from dataclasses import replace

import pytest

from causalplan import caches
from causalplan.causal.documents import SourceMap
from causalplan.causal.model import read_model
from causalplan.comparison.synthetic import synthetic_object, synthetic_task
from causalplan.objects.catalog import Catalog
from causalplan.pddl import canonical
from causalplan.pddl.canonical import MAX_MINIMAL_SETS, canonical_pddl, minimal_part_sets
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.pddl.writer import actions_text, compile_task, problem_text, requirements_line
from causalplan.planners import fd
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanStatus
from tests.conftest import example_mapping, example_model
from tests.planners.fd.test_fd import example_tasks as _example_tasks


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
    config = fd.CONFIGS["fd-opt"]
    first = fd.solve(readable.domain, readable.problem, config)
    second = fd.solve(canonical.domain, canonical.problem, config)
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
    config = fd.CONFIGS["fd"]
    assert fd.solve(big.domain, big.problem, config, time_limit=0.05).status is PlanStatus.TIMEOUT
    assert fd.solve(big.domain, big.problem, config, time_limit=60).status is PlanStatus.SOLVED


def _per_primitive_form(task: PlanningTask) -> tuple[str, str]:
    """Return the canonical form as the readable form writes its steps: one action schema per primitive."""
    compiled = canonical_pddl(task)
    assert compiled is not None
    primitives = sorted({fit.primitive for fit in task.obj.fits})
    clauses = [line for line in compiled.domain.splitlines() if line.startswith("  (:derived")]
    lines = [
        f"(define (domain causalplan-{task.obj.id})",
        requirements_line(),
        "  (:types part fit)",
        f"  (:constants {' '.join(task.obj.part_ids)} - part)",
        "  (:predicates (in-assembly ?p - part) (available ?f - fit) (moves ?f - fit ?p - part)",
        "               (attaches-to ?f - fit ?p - part) (excludes ?f - fit ?g - fit)",
        *(f"               ({primitive}-fit ?f - fit)" for primitive in primitives),
        "               (goal))",
        *clauses,
        actions_text(primitives),
        ")",
    ]
    return "\n".join(lines) + "\n", problem_text(task.obj, "goal", comments=False)


def _sas(domain: str, problem: str) -> str:
    from causalplan.planners import processes
    from causalplan.planners.fd import translate

    with processes.private_folder() as folder:
        finished = translate.translate(domain, problem, folder, 60, 2048)
        assert finished.returncode == 0, finished.output
        return (folder / translate.SAS_FILE).read_text(encoding="utf-8")


def _per_primitive_names(sas: str) -> str:
    """Rename the one-schema form's operators as the per-primitive form names them; check every one is renamed."""
    lines = sas.split("\n")
    for index, line in enumerate(lines[:-1]):
        if line == "begin_operator":
            name = lines[index + 1]
            assert name.startswith(f"{canonical.ASSEMBLE} {canonical.KIND_PREFIX}"), name
            lines[index + 1] = name.removeprefix(f"{canonical.ASSEMBLE} {canonical.KIND_PREFIX}")
    return "\n".join(lines)


def _tasks_to_compare(user_catalog: Catalog) -> dict[str, PlanningTask]:
    tasks = _example_tasks(user_catalog)
    for seed in range(4):
        for size in (3, 8, 21, 40):
            tasks[f"synthetic {size} parts, seed {seed}"] = synthetic_task(size, seed=seed)
    return tasks


def test_one_schema_translates_to_the_per_primitive_task_but_for_operator_names(
    user_catalog: Catalog, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same SAS task, operator for operator and in the same order: FD's searches cannot differ."""
    tasks = _tasks_to_compare(user_catalog)
    several_primitives = 0
    for name, task in tasks.items():
        compiled = canonical_pddl(task)
        assert compiled is not None, name
        renamed = _per_primitive_names(_sas(compiled.domain, compiled.problem))
        assert renamed == _sas(*_per_primitive_form(task)), name
        several_primitives += len({fit.primitive for fit in task.obj.fits}) > 1
    assert several_primitives >= 10  # a mixed-up order of schemas would have shown
    capsys.readouterr()  # the translator's log


@pytest.mark.slow
@pytest.mark.parametrize("config", sorted(fd.CONFIGS))
def test_plans_of_one_schema_are_those_of_the_per_primitive_form(config: str, user_catalog: Catalog) -> None:
    tasks = _tasks_to_compare(user_catalog)
    statuses = set()
    for name, task in tasks.items():
        compiled = canonical_pddl(task)
        assert compiled is not None
        caches.current().fd_answers.clear()
        one = fd.solve(compiled.domain, compiled.problem, fd.CONFIGS[config])
        per_primitive = fd.solve(*_per_primitive_form(task), fd.CONFIGS[config])
        assert one.status is per_primitive.status, name
        assert all(action == canonical.ASSEMBLE for action, _ in one.actions)
        assert canonical.plan_actions(one.actions) == per_primitive.actions, name
        statuses.add(one.status)
    assert statuses == {PlanStatus.SOLVED, PlanStatus.UNSOLVABLE}


def test_plan_actions_renames_only_the_assemble_steps() -> None:
    plan = (("assemble", ("kind-screw", "light_bulb", "base", "bulb_into_socket")), ("clip", ("shade", "base", "f")))
    assert canonical.plan_actions(plan) == (
        ("screw", ("light_bulb", "base", "bulb_into_socket")),
        ("clip", ("shade", "base", "f")),
    )


def test_an_object_without_fits_has_no_kinds_and_its_goal_is_unsolvable_or_holds(catalog: Catalog) -> None:
    lamp = catalog.get("desk_lamp")
    bare = replace(lamp, fits=())
    task = build_task(example_model("paper/desk_lamp.yaml", catalog), bare)
    compiled = canonical_pddl(task)
    assert compiled is not None and "- kind" not in compiled.domain.split("(:predicates")[0]
    outcome = fd.solve(compiled.domain, compiled.problem, fd.CONFIGS["fd"])
    assert outcome.status is PlanStatus.UNSOLVABLE
