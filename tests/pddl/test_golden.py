"""Golden files: the paper's models compiled to PDDL live under examples/pddl/.

The test fails when the compiler's output drifts from them. After a deliberate change,
regenerate with ``CAUSALPLAN_UPDATE_GOLDEN=1 pytest tests/pddl/test_golden.py`` and review the diff.
"""

from __future__ import annotations

import os

import pytest
from pddl import parse_domain, parse_problem

from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task
from causalplan.pddl.writer import compile_task
from tests.conftest import EXAMPLES, example_mapping, example_model

GOLDEN = EXAMPLES / "pddl"
CASES = {
    "desk_lamp": ("paper/desk_lamp.yaml", None),
    "desk_lamp_on_flashlight": ("paper/desk_lamp.yaml", "paper/flashlight_mapping.yaml"),
    "failed_desk_lamp": ("paper/failed_desk_lamp.yaml", None),
    "failed_desk_lamp_on_flashlight": ("paper/failed_desk_lamp.yaml", "paper/failed_flashlight_mapping.yaml"),
    "candle": ("near/candle.yaml", None),
    "candle_on_kerosene_lamp": ("near/candle.yaml", "near/kerosene_lamp_mapping.yaml"),
    "abstract_desk_lamp_on_candle": ("far/abstract_desk_lamp.yaml", "far/candle_mapping.yaml"),
}


def _compiled(case: str, catalog: Catalog) -> dict[str, str]:
    model_file, mapping_file = CASES[case]
    model = example_model(model_file, catalog)
    mapping = example_mapping(mapping_file, catalog) if mapping_file else None
    target = catalog.get(mapping.object_id if mapping else model.object_id)
    compiled = compile_task(build_task(model, target, mapping))
    return {"domain.pddl": compiled.domain, "problem.pddl": compiled.problem}


@pytest.mark.parametrize("case", sorted(CASES))
def test_compiler_output_matches_golden_files(case: str, catalog: Catalog) -> None:
    folder = GOLDEN / case
    for name, text in _compiled(case, catalog).items():
        if os.environ.get("CAUSALPLAN_UPDATE_GOLDEN"):
            folder.mkdir(parents=True, exist_ok=True)
            (folder / name).write_text(text, encoding="utf-8")
        assert (folder / name).read_text(encoding="utf-8") == text, f"{case}/{name} drifted; see this file's docstring"


@pytest.mark.parametrize("case", sorted(CASES))
def test_golden_files_parse_with_the_independent_pddl_parser(case: str) -> None:
    domain = parse_domain(GOLDEN / case / "domain.pddl")
    problem = parse_problem(GOLDEN / case / "problem.pddl")
    assert problem.domain_name == domain.name
    assert domain.derived_predicates, "the causal graph must be compiled to derived predicates"


def test_one_derived_clause_per_rule_plus_one_per_function_carrier(catalog: Catalog) -> None:
    model = example_model("paper/desk_lamp.yaml", catalog)
    domain = (GOLDEN / "desk_lamp" / "domain.pddl").read_text(encoding="utf-8")
    carrier_clauses = sum(len(parts) for parts in model.labelling.carriers().values())
    assert domain.count("(:derived ") == len(model.rules) + carrier_clauses
    assert "(:goal (n-light))" in (GOLDEN / "desk_lamp" / "problem.pddl").read_text(encoding="utf-8")


def test_every_case_has_its_folder() -> None:
    assert sorted(path.name for path in GOLDEN.iterdir() if path.is_dir()) == sorted(CASES)


def test_golden_folder_is_documented() -> None:
    readme = (GOLDEN / "README.md").read_text(encoding="utf-8")
    assert "CAUSALPLAN_UPDATE_GOLDEN=1 pytest tests/pddl/test_golden.py" in readme  # the variable this module reads
