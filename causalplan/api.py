"""The Python API: load a model and a mapping, plan, judge a transfer, simulate, the catalog.

(The transfer function is ``transfer_verdict``: a plain ``transfer`` would be shadowed by the
``causalplan.transfer`` subpackage as soon as that is imported.)

Each function takes and returns the same values the command line prints, so a notebook or a
script can do what ``causalplan plan`` and ``causalplan transfer`` do::

    import causalplan

    model = causalplan.load_model("examples/paper/desk_lamp.yaml")
    print(causalplan.plan(model).steps)
    mapping = causalplan.load_mapping("examples/paper/flashlight_mapping.yaml")
    print(causalplan.transfer_verdict(model, mapping).verdict)

Heavy modules (the planners, PyBullet) are imported inside the functions, so ``import
causalplan`` stays cheap for the command line, which imports this package first.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

from causalplan.errors import CausalPlanError

if TYPE_CHECKING:
    from causalplan.causal.diagnostics import Report
    from causalplan.causal.model import CausalModel, Labelling
    from causalplan.objects.catalog import Catalog
    from causalplan.planners.result import PlanResult
    from causalplan.sim import SimulationReport
    from causalplan.transfer.verdict import TransferVerdict


class InvalidInputError(CausalPlanError):
    """A model or mapping file is invalid; ``report`` holds every problem with its place and a hint."""

    code = "invalid_input"

    def __init__(self, message: str, report: Report) -> None:
        super().__init__(message, details=report.as_dict())
        self.report = report


def catalog(folders: Iterable[str | Path] = ()) -> Catalog:
    """Return the built-in catalog of objects, plus the object files in ``folders``."""
    from causalplan.objects.catalog import load_catalog

    return load_catalog(Path(folder) for folder in folders)


def _invalid(path: Path, kind: str, report: Report) -> InvalidInputError:
    first = report.errors[0].message if report.errors else "it could not be read"
    return InvalidInputError(f"{path}: the {kind} is invalid ({len(report.errors)} error(s)); first: {first}", report)


def load_model(path: str | Path, objects: Catalog | None = None) -> CausalModel:
    """Return the valid model in a YAML or JSON file; raise InvalidInputError with the report if it is not."""
    from causalplan.inputs import load_model as load

    loaded = load(Path(path), objects or catalog())
    if loaded.model is None or not loaded.report.is_valid:
        raise _invalid(Path(path), "model", loaded.report)
    return loaded.model


def load_mapping(path: str | Path, objects: Catalog | None = None) -> Labelling:
    """Return the valid step-3 mapping in a YAML or JSON file; raise InvalidInputError if it is not."""
    from causalplan.inputs import load_mapping as load

    loaded = load(Path(path), objects or catalog())
    if loaded.mapping is None or not loaded.report.is_valid:
        raise _invalid(Path(path), "mapping", loaded.report)
    return loaded.mapping


def plan(
    model: CausalModel,
    mapping: Labelling | None = None,
    *,
    planner: str = "auto",
    time_limit: float = 30.0,
    val: bool = True,
    objects: Catalog | None = None,
) -> PlanResult:
    """Return the replayed plan that makes the model's goal hold (on the mapping's object, if given).

    ``val`` also checks it with VAL on the readable PDDL, as the command line does by default.
    """
    from causalplan.pddl.task import catalog_task
    from causalplan.planners.pipeline import plan_task

    return plan_task(catalog_task(model, objects or catalog(), mapping), planner, time_limit, val=val)


def transfer_verdict(
    model: CausalModel,
    mapping: Labelling,
    *,
    planner: str = "auto",
    time_limit: float = 30.0,
    simulate: bool = True,
    val: bool = True,
    objects: Catalog | None = None,
) -> TransferVerdict:
    """Return whether the model transfers to the mapping's object, with every reason when it does not."""
    from causalplan.transfer.verdict import evaluate_transfer

    return evaluate_transfer(model, mapping, objects or catalog(), planner, time_limit, simulate, val)


def simulate(
    model: CausalModel,
    mapping: Labelling | None = None,
    *,
    objects: Catalog | None = None,
) -> SimulationReport:
    """Return the physics check of the model's plan: each step, stability, and whether the goal is produced."""
    from causalplan.pddl.task import catalog_task
    from causalplan.planners.pipeline import plan_task
    from causalplan.sim import RenderMode, simulate_plan

    task = catalog_task(model, objects or catalog(), mapping)
    result = plan_task(task, val=True)  # as ``plan`` checks it by default
    if not result.has_plan:
        message = f"There is no plan to simulate: {result.message}"
        raise CausalPlanError(message, details={"status": result.status.value})
    return simulate_plan(task, result.steps, render=RenderMode.NONE)
