"""The paper's misconception, found automatically: a function the true mechanism does not need,
made a necessary cause of the goal (the shade's "diffuse light" in the failed desk-lamp model).

A function is a *necessary cause* when the model's goal holds with every function of the model
but not without that one (the paper's eq. 1, computed by ``causal.graph.goal_holds``). The true
mechanism *needs* a part when the part takes part in a fit one of the object's requirements
names. A necessary function that only unneeded parts carry is the misconception.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from causalplan.causal.documents import SourceMap
from causalplan.causal.graph import goal_holds
from causalplan.errors import UnknownObjectError
from causalplan.inputs import model_from_data
from causalplan.objects.catalog import Catalog
from causalplan.objects.model import AssemblyObject


@dataclass(frozen=True)
class Misconception:
    """One necessary cause that the object's true mechanism does not need."""

    function: str
    parts: tuple[str, ...]
    object_id: str

    def as_dict(self) -> dict[str, object]:
        return {"function": self.function, "parts": list(self.parts), "object": self.object_id}

    def says(self) -> str:
        carriers = ", ".join(part.replace("_", " ") for part in self.parts)
        return (
            f"'{self.function}' (of the {carriers}) is made necessary for the goal, "
            f"but the {self.object_id.replace('_', ' ')} works without it"
        )


def needed_parts(obj: AssemblyObject) -> set[str]:
    """Return the parts that take part in a fit of the object's true mechanism."""
    parts = set()
    for requirement in obj.mechanism:
        for fit_id in requirement.any_of:
            fit = obj.fit(fit_id)
            parts |= {fit.moving_part, fit.fixed_part}
    return parts


def misconceptions(model_document: Mapping[str, Any], catalog: Catalog) -> list[Misconception]:
    """Return the model's necessary causes that its object's true mechanism does not need.

    A model that cannot be read or validated has none to report (its trial is ``invalid``).
    """
    loaded = model_from_data(dict(model_document), SourceMap(), catalog)
    if not loaded.is_valid or loaded.model is None:
        return []
    model = loaded.model
    try:
        obj = catalog.get(model.object_id)
    except UnknownObjectError:
        return []
    carriers = model.labelling.carriers()
    labels = model.labelling.labels()
    everything = set(carriers)
    if not goal_holds(everything, model.rules, model.goal_key):
        return []
    needed = needed_parts(obj)
    found = []
    for function, parts in carriers.items():
        necessary = not goal_holds(everything - {function}, model.rules, model.goal_key)
        if necessary and not needed & set(parts):
            found.append(Misconception(labels[function], parts, obj.id))
    return found
