"""A trial's model read back from a study's export, on each of its one or two training objects.

An export holds a participant's model in one of three shapes, and this module reads all three
the same way, so an analysis never skips the paper's far design (two training objects):

* a model file (``object``, ``functions`` part -> labels, ``rules``): one training object;
* the merged document of two training objects (``object: desk_lamp_and_candle``, parts
  written ``desk_lamp.base_with_cables``), as ``synthetic-study`` exports it;
* the stored participant's model (``functions``: training object -> part -> labels, no
  ``object``), as the research page exports it.

The model is checked as step 2 checks it (the rules against every training object's labels
together), then given on each training object (that object's labels, all the rules), and as
step 3 tries it on every test object: on the first training object (``tried``), as the
service does. What cannot be read is said in words (``problem``), never guessed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from causalplan.causal.diagnostics import Diagnostic
from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel, read_model
from causalplan.errors import UnknownObjectError
from causalplan.inputs import merged_model_from_data, model_from_data
from causalplan.objects.catalog import Catalog

OBJECT_SEPARATOR = "_and_"
"""What joins two training objects' ids in a merged model's ``object`` (as ``studies.steps`` writes it)."""


@dataclass(frozen=True)
class TrainedModel:
    """A trial's model on each training object, or why it could not be read (``problem``)."""

    training: tuple[str, ...]
    on_objects: Mapping[str, CausalModel] = field(default_factory=dict)
    problem: str | None = None

    @property
    def tried(self) -> CausalModel | None:
        """Return the model as step 3 tries it on a test object: on the first training object (None: unread)."""
        return self.on_objects.get(self.training[0]) if self.training and self.problem is None else None


def _grouped(
    document: Mapping[str, Any], training: Sequence[str], catalog: Catalog
) -> tuple[dict[str, Any], str | None]:
    """Return training object -> part -> labels from any of the three shapes, or why there is none."""
    functions = document.get("functions")
    if not isinstance(functions, dict) or not functions:
        return {}, "its model has no functions"
    named = document.get("object")
    if named is None:  # the stored participant's model: object -> part -> labels
        if not all(isinstance(parts, dict) for parts in functions.values()):
            return {}, "its model names no object (no 'object' field)"
        return dict(functions), None
    if not isinstance(named, str):
        return {}, "its model's 'object' is not an object id"
    objects = list(training) if len(training) > 1 else named.split(OBJECT_SEPARATOR)
    if named in catalog.objects or len(objects) < 2 or OBJECT_SEPARATOR.join(objects) != named:
        # a model file of one training object
        return {named: dict(functions)}, None
    grouped: dict[str, dict[str, Any]] = {object_id: {} for object_id in objects}
    for key, labels in functions.items():
        object_id, dot, part = str(key).partition(".")
        if not dot or object_id not in grouped:
            return {}, f"its model's part '{key}' is not written 'object.part' with one of {', '.join(objects)}"
        grouped[object_id][part] = labels
    return grouped, None


def _document(grouped: Mapping[str, Any], merged: Mapping[str, Any], object_id: str) -> dict[str, Any]:
    """Return the model file of one training object: its labels, and the merged model's goal and rules."""
    return {"object": object_id, "goal": merged["goal"], "functions": grouped[object_id], "rules": merged["rules"]}


def _first_error(report_errors: Sequence[Diagnostic]) -> str:
    """Return why a model is invalid: its first error's code and message."""
    first = report_errors[0]
    more = f" (and {len(report_errors) - 1} more)" if len(report_errors) > 1 else ""
    return f"its model is invalid: {first.code}, {first.message}{more}"


def read_trained_model(document: object, training: Sequence[str], catalog: Catalog) -> TrainedModel:
    """Return an exported trial's model on each of its training objects (``training``: the trial's order)."""
    if not isinstance(document, Mapping):
        return TrainedModel(tuple(training), problem="the trial has no model")
    grouped, problem = _grouped(document, training, catalog)
    order = tuple(grouped)
    if problem is not None:
        return TrainedModel(tuple(training), problem=problem)
    try:
        objects = [catalog.get(object_id) for object_id in order]
    except UnknownObjectError as exc:
        return TrainedModel(order, problem=f"its model's object is not in the catalog ({exc.message})")
    merged = {
        "object": OBJECT_SEPARATOR.join(order),
        "goal": document.get("goal", objects[0].goal),
        "functions": {
            (f"{object_id}.{part}" if len(order) > 1 else part): labels
            for object_id, parts in grouped.items()
            for part, labels in (parts.items() if isinstance(parts, dict) else [])
        },
        "rules": document.get("rules"),
    }
    loaded = (
        merged_model_from_data(merged, order, catalog)
        if len(order) > 1
        else model_from_data(merged, SourceMap(), catalog)
    )
    if loaded.model is None:
        return TrainedModel(order, problem=_first_error(loaded.report.diagnostics))
    if not loaded.report.is_valid:
        return TrainedModel(order, problem=_first_error(loaded.report.errors))
    on_objects = {}
    for object_id in order:
        on_object, _ = read_model(_document(grouped, merged, object_id), SourceMap())
        if on_object is None:  # pragma: no cover - a valid merged model always splits into readable ones
            return TrainedModel(order, problem=f"its model cannot be read on the {object_id}")
        on_objects[object_id] = on_object
    return TrainedModel(order, on_objects)
