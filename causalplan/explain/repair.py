"""What would make a failed transfer work: the smallest sets of edits, each re-checked by a full verdict.

Edits are on the step-3 mapping (give one of the model's functions to a part, take a label
away from a part) and on the model (drop one cause from a rule of several causes, add a
one-cause rule ``FUNCTION CAUSES EFFECT`` from labels already there). The search tries every
single edit, then every pair that contains no working single edit, and keeps a set only when
``evaluate_transfer`` (planner, replay, true mechanism, simulator) says it transfers. Most
candidates are decided by the verdict's precheck; the rest mostly share a canonical solve and
a simulation with one another, both cached.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass, replace
from enum import StrEnum
from itertools import combinations

from causalplan.causal.labels import normalize_label
from causalplan.causal.model import CausalModel, Labelling
from causalplan.causal.rules import Rule
from causalplan.objects.catalog import Catalog
from causalplan.planners.fd import DEFAULT_TIME_LIMIT
from causalplan.transfer.verdict import TransferVerdict, Verdict, evaluate_transfer, needed_functions

MAX_EDITS = 2
SHOWN = 5


class EditKind(StrEnum):
    GIVE_FUNCTION = "give_function"
    TAKE_FUNCTION = "take_function"
    DROP_CAUSE = "drop_cause"
    ADD_RULE = "add_rule"


@dataclass(frozen=True)
class Edit:
    """One edit: ``part`` and ``label`` on the mapping; ``rule`` and ``label``, or ``effect``, on the model."""

    kind: EditKind
    label: str
    part: str | None = None
    rule: int | None = None
    effect: str | None = None

    def describe(self) -> str:
        """Return the edit in words."""
        if self.kind is EditKind.GIVE_FUNCTION:
            return f"give '{self.label}' to the {self.part}"
        if self.kind is EditKind.TAKE_FUNCTION:
            return f"take '{self.label}' away from the {self.part}"
        if self.kind is EditKind.DROP_CAUSE:
            return f"drop '{self.label}' from rule {self.rule}"
        return f"add the rule '{self.label} CAUSES {self.effect}'"

    @property
    def on_mapping(self) -> bool:
        return self.kind in (EditKind.GIVE_FUNCTION, EditKind.TAKE_FUNCTION)

    def as_dict(self) -> dict[str, object]:
        return {
            "kind": self.kind.value,
            "label": self.label,
            "part": self.part,
            "rule": self.rule,
            "effect": self.effect,
            "says": self.describe(),
        }


@dataclass(frozen=True)
class Repair:
    """A set of edits that makes the model transfer, and the verdict that says so."""

    edits: tuple[Edit, ...]
    verdict: TransferVerdict

    def describe(self) -> str:
        return " and ".join(edit.describe() for edit in self.edits)

    def as_dict(self) -> dict[str, object]:
        plan = self.verdict.plan
        return {
            "size": len(self.edits),
            "edits": [edit.as_dict() for edit in self.edits],
            "says": self.describe(),
            "verdict": self.verdict.verdict.value,
            "decided_by": self.verdict.decided_by,
            "plan": [step.as_dict() for step in plan.steps] if plan is not None and plan.has_plan else None,
        }


@dataclass(frozen=True)
class RepairSearch:
    """Every minimal repair found (smallest first), how many edit sets were checked, and the limit searched to.

    ``complete``: False when the search stopped at its time budget before checking every edit set.
    """

    repairs: tuple[Repair, ...]
    checked: int
    max_edits: int
    complete: bool = True

    def shown(self, limit: int = SHOWN) -> tuple[Repair, ...]:
        return self.repairs[:limit]

    def by_size(self) -> dict[int, int]:
        """Return how many repairs have each size, from 1 to ``max_edits`` edits."""
        return {size: sum(len(r.edits) == size for r in self.repairs) for size in range(1, self.max_edits + 1)}

    def as_dict(self, limit: int = SHOWN) -> dict[str, object]:
        return {
            "found": len(self.repairs),
            "by_size": self.by_size(),
            "checked": self.checked,
            "max_edits": self.max_edits,
            "complete": self.complete,
            "repairs": [repair.as_dict() for repair in self.shown(limit)],
        }


def candidate_edits(model: CausalModel, mapping: Labelling, catalog: Catalog) -> list[Edit]:
    """Return every single edit the search tries, in a stable order."""
    test = catalog.get(mapping.object_id)
    functions = needed_functions(model)
    edits: list[Edit] = []
    for part in test.part_ids:
        have = {normalize_label(label) for label in mapping.functions.get(part, ())}
        edits += [Edit(EditKind.GIVE_FUNCTION, label, part) for key, label in functions.items() if key not in have]
    for part, labels in mapping.functions.items():
        edits += [Edit(EditKind.TAKE_FUNCTION, label, part) for label in labels]
    for rule in model.rules:
        if len(rule.causes) > 1:
            edits += [Edit(EditKind.DROP_CAUSE, cause, rule=rule.index) for cause in rule.causes]
    effects = {rule.effect_key: rule.effect for rule in model.rules}
    existing = {(next(iter(rule.cause_keys)), rule.effect_key) for rule in model.rules if len(rule.cause_keys) == 1}
    leaves = {**functions, **{k: v for k, v in mapping.labels().items() if k not in effects}}
    for key, label in sorted(leaves.items()):
        edits += [
            Edit(EditKind.ADD_RULE, label, effect=effect)
            for effect_key, effect in sorted(effects.items())
            if (key, effect_key) not in existing
        ]
    return edits


def _conflict(edits: tuple[Edit, ...]) -> bool:
    """Return whether the edits repeat or undo one another (``apply_edits`` refuses a rule left without causes)."""
    if len({(e.kind, e.part, e.rule, normalize_label(e.label)) for e in edits}) < len(edits):
        return True
    given = {(e.part, normalize_label(e.label)) for e in edits if e.kind is EditKind.GIVE_FUNCTION}
    taken = {(e.part, normalize_label(e.label)) for e in edits if e.kind is EditKind.TAKE_FUNCTION}
    return bool(given & taken)


def apply_edits(
    model: CausalModel, mapping: Labelling, edits: tuple[Edit, ...]
) -> tuple[CausalModel, Labelling] | None:
    """Return the model and mapping with ``edits`` made, or None when they leave a rule without causes."""
    functions = {part: list(labels) for part, labels in mapping.functions.items()}
    rules = {rule.index: rule for rule in model.rules}
    for edit in edits:
        if edit.kind is EditKind.GIVE_FUNCTION:
            assert edit.part is not None
            functions.setdefault(edit.part, []).append(edit.label)
        elif edit.kind is EditKind.TAKE_FUNCTION:
            assert edit.part is not None
            functions[edit.part] = [
                label for label in functions[edit.part] if normalize_label(label) != normalize_label(edit.label)
            ]
        elif edit.kind is EditKind.DROP_CAUSE:
            assert edit.rule is not None
            rule = rules[edit.rule]
            causes = tuple(c for c in rule.causes if normalize_label(c) != normalize_label(edit.label))
            if not causes:
                return None
            rules[edit.rule] = Rule(causes, rule.effect, f"{' AND '.join(causes)} CAUSES {rule.effect}", rule.index)
        else:
            assert edit.effect is not None
            index = max(rules, default=0) + 1
            rules[index] = Rule((edit.label,), edit.effect, f"{edit.label} CAUSES {edit.effect}", index)
    labelling = Labelling(mapping.object_id, {part: tuple(labels) for part, labels in functions.items() if labels})
    return replace(model, rules=tuple(rules[index] for index in sorted(rules))), labelling


def _edit_sets(edits: list[Edit], size: int, working: list[frozenset[Edit]]) -> Iterator[tuple[Edit, ...]]:
    for chosen in combinations(edits, size):
        if _conflict(chosen) or any(found <= set(chosen) for found in working):
            continue
        yield chosen


def _rank(repair: Repair, missing: set[str]) -> tuple[int, int, int, str]:
    """Smallest first; then mapping-only; then those giving a function the verdict found missing."""
    edits = repair.edits
    gives_missing = sum(e.kind is EditKind.GIVE_FUNCTION and normalize_label(e.label) in missing for e in edits)
    return (len(edits), sum(not e.on_mapping for e in edits), -gives_missing, repair.describe())


def search_repairs(
    model: CausalModel,
    mapping: Labelling,
    catalog: Catalog,
    verdict: TransferVerdict | None = None,
    max_edits: int = MAX_EDITS,
    planner: str = "fd",
    time_limit: float = DEFAULT_TIME_LIMIT,
    simulate: bool = True,
    val: bool = True,
    seconds: float | None = None,
) -> RepairSearch:
    """Return the minimal edit sets (up to ``max_edits`` edits) that make ``model`` transfer through ``mapping``.

    ``verdict`` is the failed verdict (computed when not given); a model that already
    transfers needs no repair, and the search is empty. ``seconds``: the search's budget,
    whatever ``time_limit`` is; each check gets at most what is left of it, and the search
    stops with what it found (``complete`` False) once it is spent.
    """
    deadline = time.monotonic() + seconds if seconds is not None else None
    verdict = verdict or evaluate_transfer(model, mapping, catalog, planner, time_limit, simulate, val=val)
    if verdict.verdict is not Verdict.FAILS:
        return RepairSearch((), 0, max_edits)
    missing = {
        normalize_label(label)
        for reason in verdict.reasons
        if reason.code == "missing_function"
        for label in reason.labels
    }
    edits = candidate_edits(model, mapping, catalog)
    found: list[Repair] = []
    working: list[frozenset[Edit]] = []
    checked = 0
    complete = True
    for size in range(1, max_edits + 1):
        for chosen in _edit_sets(edits, size, working):
            edited = apply_edits(model, mapping, chosen)
            if edited is None:
                continue
            limit = time_limit if deadline is None else min(time_limit, deadline - time.monotonic())
            if limit <= 0:
                complete = False
                break
            checked += 1
            result = evaluate_transfer(*edited, catalog, planner, limit, simulate, val=val)
            if result.verdict is Verdict.TRANSFERS:
                found.append(Repair(chosen, result))
        if not complete:
            break
        working = [frozenset(repair.edits) for repair in found]
    return RepairSearch(tuple(sorted(found, key=lambda r: _rank(r, missing))), checked, max_edits, complete)
