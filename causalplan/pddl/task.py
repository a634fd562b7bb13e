"""The planning task: one object, the functions its parts carry, and the rules to the goal."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from causalplan.causal.labels import normalize_label
from causalplan.causal.model import CausalModel, Labelling, node_labels
from causalplan.causal.rules import Rule
from causalplan.objects.model import AssemblyObject
from causalplan.pddl.constraints import NO_CONSTRAINTS, PlanConstraints

if TYPE_CHECKING:
    from causalplan.objects.catalog import Catalog


@dataclass(frozen=True)
class PlanningTask:
    """What the planners solve: assemble ``obj`` so the model's goal node becomes true.

    ``labelling`` says which parts carry which functions: the model's own (step 1), or a
    step-3 mapping when the model is tried on another object. ``constraints`` are a
    question's (``causalplan explain``): what the plan must also do; none by default.
    """

    obj: AssemblyObject
    labelling: Labelling
    rules: tuple[Rule, ...]
    goal: str
    constraints: PlanConstraints = NO_CONSTRAINTS

    @property
    def goal_key(self) -> str:
        return normalize_label(self.goal)

    def carriers(self) -> dict[str, tuple[str, ...]]:
        """Return each function node with the parts that carry it."""
        return self.labelling.carriers()

    def node_labels(self) -> dict[str, str]:
        """Return every node (functions carried, rule causes and effects, goal) with its label."""
        return node_labels(self.labelling, self.rules, self.goal)

    def functions_of(self, parts: set[str] | frozenset[str]) -> set[str]:
        """Return the function nodes carried by ``parts``."""
        return {label for label, carriers in self.carriers().items() if parts & set(carriers)}


def build_task(model: CausalModel, obj: AssemblyObject, mapping: Labelling | None = None) -> PlanningTask:
    """Return the task of planning ``model`` on ``obj``, with ``mapping``'s functions if given."""
    labelling = mapping if mapping is not None else model.labelling
    return PlanningTask(obj=obj, labelling=labelling, rules=model.rules, goal=model.goal)


def catalog_task(model: CausalModel, catalog: Catalog, mapping: Labelling | None = None) -> PlanningTask:
    """Return the task of planning ``model`` on its own object, or on ``mapping``'s object, from ``catalog``."""
    return build_task(model, catalog.get((mapping or model.labelling).object_id), mapping)
