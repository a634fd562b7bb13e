"""The paper's near misses, counted: per condition, how many failed transfers one or two edits would fix.

Reads an experiment export (the research page's JSON: each trial with its ``condition``,
``verdict``, ``training_order``, ``model`` and ``mapping``) and runs the repair search on every
failed trial of a participant who is not excluded. A model trained on two objects (the
paper's far design) is read as step 3 tried it on the trial's test object
(``transfer.trained``). A trial whose model or mapping cannot be read back is counted as not
checked, with the reason, never guessed.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel, Labelling
from causalplan.errors import CausalPlanError
from causalplan.explain.repair import search_repairs
from causalplan.inputs import mapping_from_data
from causalplan.objects.catalog import Catalog
from causalplan.transfer.trained import read_trained_model

COMMON_EDITS = 3
"""How many of a condition's most frequent fixing edits are named."""


@dataclass
class NearMisses:
    """One condition's failed trials: how many one edit fixes, how many two, and the edits that do."""

    condition: str
    failed: int = 0
    one_edit: int = 0
    two_edits: int = 0
    edits: Counter[str] = field(default_factory=Counter)
    """Per edit (in words), in how many failed trials it is part of a smallest repair."""
    not_checked_because: Counter[str] = field(default_factory=Counter)
    """Why failed trials were not checked (in words), and how many for each reason."""

    @property
    def not_checked(self) -> int:
        return sum(self.not_checked_because.values())

    def why_not_checked(self) -> str:
        """Return the reasons trials were not checked, most frequent first ('' when all were)."""
        return "; ".join(f"{reason} ({count})" for reason, count in self.not_checked_because.most_common())

    def summary(self) -> str:
        """Return the condition's near misses in one sentence, saying why any trial was not checked."""
        checked = self.failed - self.not_checked
        if checked == 0:
            return (
                f"{self.condition}: none of its {self.failed} failed transfer(s) could be checked: "
                f"{self.why_not_checked()}."
            )
        common = "; ".join(f"{words} ({count})" for words, count in self.edits.most_common(COMMON_EDITS))
        words = (
            f"{self.condition}: {self.one_edit} of {checked} failed transfers are fixed by one edit, "
            f"{self.two_edits} more by two"
        )
        words += f"; most often: {common}" if common else ""
        return words + (f" ({self.not_checked} not checked: {self.why_not_checked()})." if self.not_checked else ".")

    def as_dict(self) -> dict[str, object]:
        return {
            "condition": self.condition,
            "failed": self.failed,
            "one_edit": self.one_edit,
            "two_edits": self.two_edits,
            "not_checked": self.not_checked,
            "not_checked_because": dict(self.not_checked_because.most_common()),
            "edits": dict(self.edits.most_common()),
            "summary": self.summary(),
        }


def _excluded(export: Mapping[str, Any]) -> set[str]:
    participants = export.get("participants")
    if not isinstance(participants, list):
        return set()
    return {str(item.get("participant_id")) for item in participants if isinstance(item, dict) and item.get("excluded")}


def _trial_inputs(item: Mapping[str, Any], catalog: Catalog) -> tuple[CausalModel, Labelling] | str:
    """Return a failed trial's model (as step 3 tried it) and mapping, or why they cannot be checked."""
    training = item.get("training_order")
    trained = read_trained_model(
        item.get("model"), [str(name) for name in training] if isinstance(training, list) else [], catalog
    )
    if trained.tried is None:
        return trained.problem or "its model cannot be read"
    if item.get("mapping") is None:
        return "the export has no mapping for the trial"
    mapping = mapping_from_data(item.get("mapping"), SourceMap(), catalog)
    if mapping.mapping is None or not mapping.is_valid:
        first = mapping.report.errors[0] if mapping.report.errors else None
        return f"its mapping is invalid: {first.code}, {first.message}" if first else "its mapping is invalid"
    return trained.tried, mapping.mapping


def near_misses(export: Mapping[str, Any], catalog: Catalog, simulate: bool = True) -> list[NearMisses]:
    """Return, per condition in the order met, the near misses among the export's failed trials."""
    trials = export.get("trials")
    found: dict[str, NearMisses] = {}
    excluded = _excluded(export)
    for item in trials if isinstance(trials, list) else []:
        if not isinstance(item, dict) or item.get("verdict") != "fails":
            continue
        if str(item.get("participant_id")) in excluded:
            continue
        counts = found.setdefault(str(item.get("condition")), NearMisses(str(item.get("condition"))))
        counts.failed += 1
        inputs = _trial_inputs(item, catalog)
        if isinstance(inputs, str):
            counts.not_checked_because[inputs] += 1
            continue
        try:
            search = search_repairs(*inputs, catalog, simulate=simulate)
        except CausalPlanError as exc:
            counts.not_checked_because[f"the repair search stopped: {exc.code}"] += 1
            continue
        if not search.repairs:
            continue
        smallest = min(len(repair.edits) for repair in search.repairs)
        counts.one_edit += smallest == 1
        counts.two_edits += smallest == 2
        counts.edits.update(
            {edit.describe() for repair in search.repairs if len(repair.edits) == smallest for edit in repair.edits}
        )
    return list(found.values())


def summaries(found: Sequence[NearMisses]) -> list[str]:
    """Return one sentence per condition."""
    return [counts.summary() for counts in found]
