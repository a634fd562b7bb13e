"""The paper's near misses, counted: per condition, how many failed transfers one or two edits would fix.

Reads an experiment export (the research page's JSON: each trial with its ``condition``,
``verdict``, ``model`` and ``mapping``) and runs the repair search on every failed trial of a
participant who is not excluded. A trial whose model or mapping cannot be read back (e.g. a
model over several training objects, whose merged object is not in the catalog) is counted
as not checked, never guessed.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from causalplan.causal.documents import SourceMap
from causalplan.errors import CausalPlanError
from causalplan.explain.repair import search_repairs
from causalplan.inputs import mapping_from_data, model_from_data
from causalplan.objects.catalog import Catalog

COMMON_EDITS = 3
"""How many of a condition's most frequent fixing edits are named."""


@dataclass
class NearMisses:
    """One condition's failed trials: how many one edit fixes, how many two, and the edits that do."""

    condition: str
    failed: int = 0
    one_edit: int = 0
    two_edits: int = 0
    not_checked: int = 0
    edits: Counter[str] = field(default_factory=Counter)
    """Per edit (in words), in how many failed trials it is part of a smallest repair."""

    def summary(self) -> str:
        """Return the condition's near misses in one sentence."""
        checked = self.failed - self.not_checked
        common = "; ".join(f"{words} ({count})" for words, count in self.edits.most_common(COMMON_EDITS))
        words = (
            f"{self.condition}: {self.one_edit} of {checked} failed transfers are fixed by one edit, "
            f"{self.two_edits} more by two"
        )
        words += f"; most often: {common}" if common else ""
        return words + (f" ({self.not_checked} not checked)." if self.not_checked else ".")

    def as_dict(self) -> dict[str, object]:
        return {
            "condition": self.condition,
            "failed": self.failed,
            "one_edit": self.one_edit,
            "two_edits": self.two_edits,
            "not_checked": self.not_checked,
            "edits": dict(self.edits.most_common()),
            "summary": self.summary(),
        }


def _excluded(export: Mapping[str, Any]) -> set[str]:
    participants = export.get("participants")
    if not isinstance(participants, list):
        return set()
    return {str(item.get("participant_id")) for item in participants if isinstance(item, dict) and item.get("excluded")}


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
        model = model_from_data(item.get("model"), SourceMap(), catalog)
        mapping = mapping_from_data(item.get("mapping"), SourceMap(), catalog)
        if model.model is None or mapping.mapping is None or not (model.is_valid and mapping.is_valid):
            counts.not_checked += 1
            continue
        try:
            search = search_repairs(model.model, mapping.mapping, catalog, simulate=simulate)
        except CausalPlanError:
            counts.not_checked += 1
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
