"""What one participant works on: the stages, the saved work, and their causal model and mappings.

A participant's model is their step-1 labels of each training object and one set of step-2
rules. With one training object it is exactly a model file, checked by the same reader and
validation as ``causalplan check`` (same codes and messages). With two, the rules must explain
both: they are checked once against the two objects' labels together (part ids written
``object.part``), and each object must produce the goal with its own parts' functions.

Everything here takes and returns values; storing them is ``store``'s job.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from causalplan.causal.diagnostics import Diagnostic, Report, error
from causalplan.causal.documents import SourceMap
from causalplan.causal.graph import goal_holds
from causalplan.causal.labels import display_label, normalize_label
from causalplan.causal.model import CausalModel, read_model
from causalplan.causal.validation import ObjectSummary, validate_model
from causalplan.inputs import LoadedMapping, LoadedModel, mapping_from_data, model_from_data
from causalplan.limits import LimitExceededError, check_labelling_limits, check_model_limits
from causalplan.objects.catalog import Catalog
from causalplan.objects.model import AssemblyObject
from causalplan.settings import Settings


class Stage(StrEnum):
    """Where a participant is, in the order they go through it."""

    TUTORIAL = "tutorial"
    STEP1 = "step1"  # label the parts of each training object with functions
    STEP2 = "step2"  # one set of rules for the training objects
    STEP3 = "step3"  # map each test object's parts to the model's functions
    ABOUT = "about"  # the experiment's optional demographic questions
    DONE = "done"
    SCREENED = "screened"  # screened out by the comprehension check: the study ends here


def labels_from_text(text: str) -> list[str]:
    """Return the labels of a 'one function per line' box: non-empty lines, spaces tidied."""
    return [display_label(line) for line in text.splitlines() if line.strip()]


def rules_from_text(text: str) -> tuple[list[str], list[int]]:
    """Return the rules of the rule box (non-empty lines) and the 1-based line of each."""
    rules: list[str] = []
    lines: list[int] = []
    for number, line in enumerate(text.splitlines(), start=1):
        if line.strip():
            rules.append(line.strip())
            lines.append(number)
    return rules, lines


@dataclass(frozen=True)
class ParticipantModel:
    """Steps 1 and 2 of one participant: labels per training object (in their order) and the rules."""

    goal: str
    functions: Mapping[str, Mapping[str, Sequence[str]]]
    """Training object id -> part id -> function labels."""
    rules: tuple[str, ...]

    @property
    def object_ids(self) -> tuple[str, ...]:
        return tuple(self.functions)

    @property
    def merged_id(self) -> str:
        """Return the id the model goes by: the training object's, or ``a_and_b`` for two."""
        return "_and_".join(self.object_ids)

    def document(self, object_id: str) -> dict[str, Any]:
        """Return the model file of one training object: its labels and all the rules."""
        return {
            "object": object_id,
            "goal": self.goal,
            "functions": {part: list(labels) for part, labels in self.functions[object_id].items() if labels},
            "rules": list(self.rules),
        }

    def merged_document(self) -> dict[str, Any]:
        """Return one document with every training object's labels (parts named ``object.part``)."""
        if len(self.object_ids) == 1:
            return self.document(self.object_ids[0])
        return {
            "object": self.merged_id,
            "goal": self.goal,
            "functions": {
                f"{object_id}.{part}": list(labels)
                for object_id, parts in self.functions.items()
                for part, labels in parts.items()
                if labels
            },
            "rules": list(self.rules),
        }

    def function_labels(self) -> list[str]:
        """Return the distinct function labels of step 1, first spelling kept, in the order given."""
        seen: dict[str, str] = {}
        for parts in self.functions.values():
            for labels in parts.values():
                for label in labels:
                    seen.setdefault(normalize_label(label), display_label(label))
        return list(seen.values())

    def as_dict(self) -> dict[str, Any]:
        """Return the model as stored with the participant (and exported)."""
        return {
            "goal": self.goal,
            "functions": {
                object_id: {p: list(ls) for p, ls in parts.items()} for object_id, parts in self.functions.items()
            },
            "rules": list(self.rules),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ParticipantModel:
        """Return the model stored by ``as_dict``."""
        return cls(str(data["goal"]), data["functions"], tuple(data["rules"]))


def _limits_report(check_limits: Callable[[], None]) -> Report | None:
    """Return the report of a document over the service's limits (None when within them)."""
    try:
        check_limits()
    except LimitExceededError as exc:
        return Report((error(exc.code, exc.message),))
    return None


def check_model(participant_model: ParticipantModel, catalog: Catalog, settings: Settings) -> LoadedModel:
    """Validate a participant's model (the service's limits first); return it (to draw) with the report."""
    document = participant_model.merged_document()
    over = _limits_report(lambda: check_model_limits(document, settings))
    if over is not None:
        return LoadedModel(None, over)
    if len(participant_model.object_ids) == 1:
        return model_from_data(document, SourceMap(), catalog)
    model, problems = read_model(document, SourceMap())
    if model is None:
        return LoadedModel(None, Report(tuple(problems)))
    objects = [catalog.get(object_id) for object_id in participant_model.object_ids]
    summary = ObjectSummary(
        participant_model.merged_id,
        tuple(document["functions"]),
        objects[0].goal,
        " and ".join(obj.name for obj in objects),
    )
    report = validate_model(model, {summary.id: summary}, problems)
    if report.is_valid:
        report = report.merged(Report(tuple(_unexplained(participant_model, model, objects))))
    return LoadedModel(model, report)


def _unexplained(
    participant_model: ParticipantModel, model: CausalModel, objects: list[AssemblyObject]
) -> list[Diagnostic]:
    """Return an error for each training object whose own functions do not produce the goal."""
    problems = []
    for obj in objects:
        functions = {
            normalize_label(label) for labels in participant_model.functions[obj.id].values() for label in labels
        }
        if not goal_holds(functions, model.rules, model.goal_key):
            problems.append(
                error(
                    "object_not_explained",
                    f"With the functions of the {obj.name}'s parts, no chain of rules produces {model.goal}.",
                    hint=f"One model must explain both objects: add a rule whose causes are functions of the "
                    f"{obj.name}'s parts, or give its parts the functions your rules use (step 1).",
                )
            )
    return problems


def model_on(participant_model: ParticipantModel, object_id: str) -> CausalModel:
    """Return the (validated) model as the planner sees it on one training object."""
    model, _ = read_model(participant_model.document(object_id), SourceMap())
    assert model is not None, "a document built from a model always reads"
    return model


def rule_lines(report: Report, lines: Sequence[int]) -> list[dict[str, object]]:
    """Return the report's diagnostics as dicts, each with the line of the rule box it is about."""
    found: list[dict[str, object]] = []
    for diagnostic in report.diagnostics:
        item = diagnostic.as_dict()
        rule = diagnostic.location.rule
        item["line"] = lines[rule - 1] if rule is not None and 0 < rule <= len(lines) else None
        found.append(item)
    return found


@dataclass(frozen=True)
class MappingCheck(LoadedMapping):
    """A step-3 mapping read and validated (``LoadedMapping``), with the document it was read from."""

    document: dict[str, Any]


def mapping_document(obj: AssemblyObject, entries: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    """Return the mapping file of a test object from step 3's entries (chosen labels and new lines)."""
    functions: dict[str, list[str]] = {}
    for part in obj.part_ids:
        entry = entries.get(part, {})
        labels = [*entry.get("chosen", []), *labels_from_text(str(entry.get("added", "")))]
        if labels:
            functions[part] = labels
    return {"object": obj.id, "functions": functions}


def check_mapping(document: dict[str, Any], catalog: Catalog, settings: Settings) -> MappingCheck:
    """Validate a step-3 mapping (limits, the reader, and at least one function given)."""
    over = _limits_report(lambda: check_labelling_limits(document, settings, "mapping"))
    if over is not None:
        return MappingCheck(None, over, document)
    loaded = mapping_from_data(document, SourceMap(), catalog)
    report = loaded.report
    if not document["functions"]:
        report = report.merged(
            Report(
                (
                    error(
                        "empty_mapping",
                        "No part has a function yet.",
                        hint="Tick the functions each part has (or add new ones) before you submit.",
                    ),
                )
            )
        )
    return MappingCheck(loaded.mapping, report, document)


UNUSABLE_LABEL_CODES = ("keyword_in_label",)
"""Step-1 warnings a participant sees before going on: a label no rule will ever be able to name."""


def unusable_label_notes(report: Report) -> str:
    """Return a fingerprint of the report's unusable-label warnings ('' when there are none).

    The step-1 page shows them once and sends the fingerprint back with the form: the same
    labels sent again go on, changed ones that still hold a keyword are shown again.
    """
    messages = [d.message for d in report.warnings if d.code in UNUSABLE_LABEL_CODES]
    if not messages:
        return ""
    return hashlib.sha256("\n".join(messages).encode("utf-8", "surrogatepass")).hexdigest()[:16]


def check_functions(obj: AssemblyObject, texts: Mapping[str, str], catalog: Catalog, settings: Settings) -> Report:
    """Validate step 1 of one training object: the labels as a model file's ``functions`` would be read."""
    document = {
        "object": obj.id,
        "functions": {
            part: labels_from_text(texts.get(part, "")) for part in obj.part_ids if texts.get(part, "").strip()
        },
    }
    checked = check_mapping(document, catalog, settings)
    if "empty_mapping" in checked.report.codes():
        others = tuple(d for d in checked.report.diagnostics if d.code != "empty_mapping")
        return Report(
            (
                *others,
                error(
                    "no_functions",
                    f"No part of the {obj.name} has a function yet.",
                    hint=f"Write what the parts do to produce {obj.goal}, one function per line.",
                ),
            )
        )
    return checked.report
