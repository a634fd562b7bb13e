"""VAL on the golden examples: their plans are valid, mutated plans are rejected in VAL's words."""

from __future__ import annotations

import pytest

from causalplan import caches
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners import val
from causalplan.planners.pipeline import plan_task
from causalplan.planners.result import PlanStatus
from causalplan.planners.val import PlanRejectedError, ValidatorError, ValVerdict
from tests.conftest import EXAMPLES, example_mapping, example_model
from tests.pddl.test_golden import CASES

GOLDEN = EXAMPLES / "pddl"
FLASHLIGHT = GOLDEN / "desk_lamp_on_flashlight"
BATTERIES = ("insert", ("batteries", "case", "batteries_into_bay"))
HEAD = ("screw", ("head", "case", "head_onto_case"))


def _golden(case: str) -> tuple[str, str]:
    folder = GOLDEN / case
    return (folder / "domain.pddl").read_text(encoding="utf-8"), (folder / "problem.pddl").read_text(encoding="utf-8")


def _task(case: str, catalog: Catalog) -> PlanningTask:
    model_file, mapping_file = CASES[case]
    model = example_model(model_file, catalog)
    mapping = example_mapping(mapping_file, catalog) if mapping_file else None
    return build_task(model, catalog.get(mapping.object_id if mapping else model.object_id), mapping)


def test_val_accepts_the_plan_of_every_golden_example_that_has_one(catalog: Catalog) -> None:
    planned = 0
    for case in sorted(CASES):
        result = plan_task(_task(case, catalog), "fd")
        if result.status is not PlanStatus.SOLVED:
            continue
        actions = [(step.action, (*step.args, step.fit)) for step in result.steps]
        assert val.validate(*_golden(case), actions) == val.ValReport(ValVerdict.VALID), case
        planned += 1
    assert planned >= 5


@pytest.mark.parametrize(
    ("mutation", "actions", "words"),
    [
        ("a step dropped", [HEAD], "Goal not satisfied"),
        ("a blocked order", [HEAD, BATTERIES], "has an unsatisfied precondition"),
        ("a wrong fit", [("insert", ("batteries", "case", "head_onto_case")), HEAD], "unsatisfied precondition"),
    ],
)
def test_val_rejects_mutated_plans_in_its_own_words(
    mutation: str, actions: list[tuple[str, tuple[str, ...]]], words: str
) -> None:
    report = val.validate(*_golden("desk_lamp_on_flashlight"), actions)
    assert report.verdict is ValVerdict.INVALID, mutation
    assert words in report.words, report.words
    assert val.validate(*_golden("desk_lamp_on_flashlight"), [BATTERIES, HEAD]).verdict is ValVerdict.VALID


def test_a_rejected_plan_is_an_error_with_a_stable_code_and_vals_words() -> None:
    with pytest.raises(PlanRejectedError) as raised:
        val.check(*_golden("desk_lamp_on_flashlight"), [HEAD])
    assert raised.value.code == "plan_rejected_by_val"
    assert "(Satisfy derived predicate (n-light)!)" in raised.value.message


def test_a_task_val_cannot_read_is_a_validator_error_not_a_verdict() -> None:
    domain, _problem = _golden("desk_lamp_on_flashlight")
    report = val.validate(domain, "(define (problem broken", [BATTERIES])
    assert report.verdict is ValVerdict.ERROR
    with pytest.raises(ValidatorError):
        val.check(domain, "(define (problem broken", [BATTERIES])


def test_a_verdict_is_kept_by_task_key_so_other_wordings_of_one_task_run_val_once(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    runs: list[str] = []
    real = val._run_validate

    def counted(domain: str, problem: str, plan: str) -> val.ValReport:
        runs.append(domain)
        return real(domain, problem, plan)

    monkeypatch.setattr(val, "_run_validate", counted)
    from causalplan.causal.documents import SourceMap
    from causalplan.causal.model import read_model

    for words in ("give power", "supply electricity"):
        model, _ = read_model(
            {
                "object": "desk_lamp",
                "functions": {"base_with_cables": [words], "light_bulb": ["glow"]},
                "rules": [f"{words} AND glow CAUSES light"],
            },
            SourceMap(),
        )
        assert model is not None
        assert plan_task(build_task(model, catalog.get("desk_lamp")), "fd", val=True).validated_by["val"] == "valid"
    assert len(runs) == 1 and "give-power" in runs[0]


def test_a_verdict_is_kept_so_a_repeated_plan_runs_val_once(monkeypatch: pytest.MonkeyPatch) -> None:
    runs: list[str] = []
    real = val._run_validate

    def counted(domain: str, problem: str, plan: str) -> val.ValReport:
        runs.append(plan)
        return real(domain, problem, plan)

    monkeypatch.setattr(val, "_run_validate", counted)
    for _ in range(3):
        assert val.validate(*_golden("desk_lamp_on_flashlight"), [BATTERIES, HEAD]).verdict is ValVerdict.VALID
    assert runs == ["(insert batteries case batteries_into_bay)\n(screw head case head_onto_case)\n"]


def test_plan_task_with_val_says_so_and_a_plan_val_rejects_is_never_returned(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    task = _task("desk_lamp_on_flashlight", catalog)
    result = plan_task(task, "fd", val=True)
    assert result.validated_by == {"replay": "valid", "val": "valid"}
    assert result.as_dict()["validated_by"] == {"replay": "valid", "val": "valid"}
    assert plan_task(task, "fd").validated_by == {"replay": "valid"}
    # VAL checks the readable PDDL, not the canonical form FD solved: a readable task with
    # the goal made unreachable (as a mistranslation of the rules would) is caught there.
    from dataclasses import replace

    from causalplan.pddl.writer import CompiledTask
    from causalplan.planners import pipeline

    real_compile = pipeline.compile_task

    def negated_goal(planning_task: PlanningTask) -> CompiledTask:
        compiled = real_compile(planning_task)
        return replace(compiled, problem=compiled.problem.replace("(:goal (n-light))", "(:goal (not (n-light)))"))

    monkeypatch.setattr(pipeline, "compile_task", negated_goal)
    caches.current().val_verdicts.clear()  # kept by canonical form, which the wrong goal leaves as it was
    with pytest.raises(PlanRejectedError, match="Goal not satisfied"):
        plan_task(task, "fd", val=True)
