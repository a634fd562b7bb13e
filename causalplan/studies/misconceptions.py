"""The paper's misconception, found automatically: a function the true mechanism does not need,
made a necessary cause of the goal (the shade's "diffuse light" in the failed desk-lamp model).

A function is a *necessary cause* when the model's goal holds with every function of the model
but not without that one (the paper's eq. 1, computed by ``causal.graph.goal_holds``). The true
mechanism *needs* a part when the part takes part in a fit one of the object's requirements
names. A necessary function that only unneeded parts carry is the misconception.

A model trained on two objects (the paper's far design) is checked on each training object:
that object's labels, all the rules, that object's true mechanism (``transfer.trained`` reads
every shape an export holds). A model that cannot be checked says why (``not_checked``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from causalplan.causal.graph import goal_holds
from causalplan.causal.model import CausalModel
from causalplan.objects.catalog import Catalog
from causalplan.objects.model import AssemblyObject
from causalplan.transfer.trained import read_trained_model


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


@dataclass(frozen=True)
class MisconceptionCheck:
    """What the check of one participant's model found, or why it could not be made (``not_checked``)."""

    found: tuple[Misconception, ...] = ()
    not_checked: str | None = None


def _on_object(model: CausalModel, obj: AssemblyObject) -> list[Misconception]:
    """Return the necessary causes of ``model`` (on ``obj``'s labels) that ``obj``'s true mechanism does not need."""
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


def check_misconceptions(
    model_document: Mapping[str, Any], catalog: Catalog, training: Sequence[str] = ()
) -> MisconceptionCheck:
    """Return the model's necessary causes that a training object's true mechanism does not need.

    ``training`` is the trial's training order (the export's ``training_order``); a model file
    names its one object itself. Each training object is checked with its own labels.
    """
    trained = read_trained_model(model_document, training, catalog)
    if trained.problem is not None:
        return MisconceptionCheck(not_checked=trained.problem)
    found = [
        item for object_id, model in trained.on_objects.items() for item in _on_object(model, catalog.get(object_id))
    ]
    return MisconceptionCheck(tuple(found))


def misconceptions(
    model_document: Mapping[str, Any], catalog: Catalog, training: Sequence[str] = ()
) -> list[Misconception]:
    """Return the model's misconceptions (none for a model that cannot be checked: see ``check_misconceptions``)."""
    return list(check_misconceptions(model_document, catalog, training).found)
