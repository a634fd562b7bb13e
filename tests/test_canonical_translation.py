"""The canonical form's shorter translation writes exactly the SAS task of FD's full translator."""

from __future__ import annotations

import io
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from causalplan.objects.catalog import Catalog
from causalplan.objects.model import AssemblyObject
from causalplan.pddl.canonical import ASSEMBLE_SCHEMA, canonical_pddl, canonical_texts
from causalplan.pddl.writer import compile_task
from causalplan.planners import canonical_translation, fast_downward
from causalplan.planners.synthetic import synthetic_task
from tests.test_search_processes import _example_tasks


@pytest.fixture(autouse=True)
def _no_halves_kept() -> Iterator[None]:
    canonical_translation.clear()
    yield
    canonical_translation.clear()


def _canonical_sas(domain: str, problem: str) -> str | None:
    """Return the SAS text of the shorter way, or None where it does not apply."""
    from fast_downward.translate import options

    options.options = fast_downward.translator_options()
    task = canonical_translation.sas_task(domain, problem)
    if task is None:
        return None
    text = io.StringIO()
    task.output(text)
    return text.getvalue()


def _full_sas(domain: str, problem: str, monkeypatch: pytest.MonkeyPatch) -> tuple[int, str | None]:
    """Return the exit code and SAS text of the in-process translator without the shorter way."""
    with monkeypatch.context() as patch:
        patch.setattr(canonical_translation, "sas_task", lambda domain, problem: None)
        return fast_downward._run_translator(domain, problem)


def _same_as_full(domain: str, problem: str, monkeypatch: pytest.MonkeyPatch) -> str:
    ours = _canonical_sas(domain, problem)
    code, full = _full_sas(domain, problem, monkeypatch)
    assert code == 0
    assert ours is not None, "the canonical form should take the shorter way"
    assert ours == full
    return ours


def test_every_example_translates_to_the_full_translators_task(
    user_catalog: Catalog, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    tasks = _example_tasks(user_catalog)
    compared = 0
    for name, task in tasks.items():
        compiled = canonical_pddl(task)
        if compiled is None:
            continue
        for _ in range(2):  # the second time from the object's kept half
            assert (
                _canonical_sas(compiled.domain, compiled.problem)
                == _full_sas(compiled.domain, compiled.problem, monkeypatch)[1]
            ), name
        compared += 1
    assert compared >= 30
    capsys.readouterr()  # the translator's log


@pytest.mark.parametrize(("size", "seed"), [(4, 1), (25, 3), (80, 0)])
def test_synthetic_tasks_translate_to_the_translators_own_process_output(size: int, seed: int, tmp_path: Path) -> None:
    compiled = canonical_pddl(synthetic_task(size, seed=seed))
    assert compiled is not None
    (tmp_path / "domain.pddl").write_text(compiled.domain, encoding="utf-8")
    (tmp_path / "problem.pddl").write_text(compiled.problem, encoding="utf-8")
    command = [sys.executable, "-m", "fast_downward.translate", "domain.pddl", "problem.pddl", "--sas-file", "out.sas"]
    subprocess.run(command, cwd=tmp_path, check=True, capture_output=True)
    assert _canonical_sas(compiled.domain, compiled.problem) == (tmp_path / "out.sas").read_text(encoding="utf-8")


_OBJECTS = {
    "desk lamp": lambda catalog: catalog.get("desk_lamp"),
    "kerosene lamp": lambda catalog: catalog.get("kerosene_lamp"),
    "synthetic 12": lambda _: synthetic_task(12, seed=4).obj,
    "synthetic 30": lambda _: synthetic_task(30, seed=7).obj,
}


@st.composite
def _goals(draw: st.DrawFn, obj: AssemblyObject) -> list[list[str]]:
    """Minimal-set-like goals over ``obj``'s parts: none, the empty set, unreachable parts, overlaps."""
    parts = st.lists(st.sampled_from(obj.part_ids), max_size=4, unique=True)
    return draw(st.lists(parts, max_size=5))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_any_goal_on_a_kept_object_translates_to_the_full_translators_task(
    data: st.DataObject, catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Goals change from one translation to the next while each object's half is kept (and reused)."""
    name = data.draw(st.sampled_from(sorted(_OBJECTS)))
    obj = _OBJECTS[name](catalog)
    _same_as_full(*canonical_texts(obj, data.draw(_goals(obj))), monkeypatch)  # Hypothesis shows the draws


def test_an_unreachable_goal_is_the_same_unsolvable_task(catalog: Catalog, monkeypatch: pytest.MonkeyPatch) -> None:
    obj = catalog.get("candle")
    _same_as_full(*canonical_texts(obj, []), monkeypatch)  # no clause: the goal never holds
    domain, problem = canonical_texts(obj, [["wick"]])
    (wick_fit,) = [fit.id for fit in obj.fits if fit.moving_part == "wick"]
    without_wick = problem.replace(f"(available {wick_fit})", "")  # the wick can never join
    assert without_wick != problem
    assert "end_goal" in _same_as_full(domain, without_wick, monkeypatch)


def test_a_goal_on_an_undefined_part_is_the_translators_input_error(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    domain, problem = canonical_texts(catalog.get("candle"), [["no_such_part"]])
    code, sas = fast_downward._run_translator(domain, problem)
    assert (code, sas) == (fast_downward.TRANSLATE_INPUT_ERROR, None) == _full_sas(domain, problem, monkeypatch)


def test_only_the_canonical_form_takes_the_shorter_way(catalog: Catalog, monkeypatch: pytest.MonkeyPatch) -> None:
    from causalplan.pddl.task import build_task
    from tests.conftest import example_model

    task = build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp"))
    readable = compile_task(task)
    assert _canonical_sas(readable.domain, readable.problem) is None  # no assemble schema
    canonical = canonical_pddl(task)
    assert canonical is not None
    # A schema that is not the one the walk grounds (here: a second positive precondition on the
    # moving part) is left to FD's Datalog grounding, which gives the right answer.
    changed_schema = ASSEMBLE_SCHEMA.replace("(available ?fit)", "(available ?fit) (in-assembly ?moving)")
    assert changed_schema != ASSEMBLE_SCHEMA
    changed = canonical.domain.replace(ASSEMBLE_SCHEMA, changed_schema)
    assert canonical_translation.sas_task(changed, canonical.problem) is None
    code, sas = fast_downward._run_translator(changed, canonical.problem)
    assert code == 0 and sas is not None and sas != _full_sas(canonical.domain, canonical.problem, monkeypatch)[1]


def test_a_goal_clause_of_another_shape_is_left_to_the_full_translator(catalog: Catalog) -> None:
    domain, problem = canonical_texts(catalog.get("candle"), [["wick"]])
    negated = domain.replace("(:derived (goal) (in-assembly wick))", "(:derived (goal) (not (in-assembly wick)))")
    assert negated != domain
    assert canonical_translation.sas_task(negated, problem) is None


def test_the_kept_halves_are_bounded(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(canonical_translation, "OBJECTS_KEPT", 3)
    for seed in range(5):
        obj = synthetic_task(6, seed=seed).obj
        assert _canonical_sas(*canonical_texts(obj, [[obj.part_ids[-1]]])) is not None
    assert len(canonical_translation._halves) == 3


def test_tasks_without_a_carried_exploration_are_explored_by_fd(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """Once the hook is in, the readable form still translates as the translator's own process does."""
    from fast_downward.translate import instantiate

    from tests.test_fast_downward import _sas_of_the_translators_own_process

    _same_as_full(*canonical_texts(catalog.get("candle"), [["wick"]]), monkeypatch)
    explore: Any = instantiate.explore
    assert getattr(explore, "carries_causalplan_exploration", False)
    task = synthetic_task(9, seed=2)
    readable = compile_task(task)
    code, sas = fast_downward._run_translator(readable.domain, readable.problem)
    assert code == 0 and sas == _sas_of_the_translators_own_process(task, tmp_path)


def test_a_kept_object_is_not_parsed_again_for_its_first_model(
    catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    from causalplan.pddl.task import build_task
    from tests.conftest import example_model

    canonical_translation.keep_object(catalog.get("desk_lamp"))

    def parse_again(domain: str, problem: str) -> None:
        raise AssertionError("the object's half should have been kept")

    monkeypatch.setattr(canonical_translation, "_read_object_half", parse_again)
    compiled = canonical_pddl(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    assert compiled is not None
    assert _canonical_sas(compiled.domain, compiled.problem) is not None
