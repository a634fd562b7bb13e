"""How plausible a participant's step-3 mapping is: is each function given to a part like what parts of that kind do?

An all-electric model "transfers" to the candle when the participant gives "close the circuit"
to the match: the planner only checks that the mapping makes the model's rules true. So each
(part, function) pair of a mapping is scored by the label alignment the consensus uses
(``alignment.word_similarity``: static embeddings or character overlap, the larger), against
the catalog's own functions (the expert's words for each requirement of an object's true
mechanism, on the parts its fits join):

- ``same``: the best likeness to a function of the part itself, or of any object of the test
  object's category (a candle's match may "start the fire" like a kerosene lamp's lighter);
- ``other``: the best likeness to a function of an object of another category (electric
  against combustion).

A pair's score is ``same / (same + other)``: 0.5 when the label is as like the other category's
functions as its own, lower when it belongs to the other category. A mapping's score is its
lowest pair's (a transfer rests on every function it maps). Below ``THRESHOLD`` a mapping is
implausible. The threshold separates, on the paper's objects, "close the circuit" on the match
(0.31), "turn electricity into light" on the candle's wick (0.31) and "provide electricity" on
a combustion object's parts (0.39) from the own-category mappings of
``tests/consensus/test_plausibility.py`` (0.47 and over, e.g. "supply power" on the batteries,
"make light" on the wick), which holds all these examples: a handful, not a study's mappings.
The part half of the alignment's similarity is left out: the label sits on the part the
participant chose, so it would say nothing.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from causalplan.consensus.alignment import word_similarity
from causalplan.objects.catalog import Catalog
from causalplan.objects.model import AssemblyObject

THRESHOLD = 0.42
"""A mapping scoring below this is implausible (see the module's text for how it was chosen)."""


@dataclass(frozen=True)
class PairScore:
    """One function given to one part, scored."""

    part: str
    label: str
    score: float
    nearest_same: str
    """The catalog function of the test object's category (or the part's own) most like the label."""
    nearest_other: str
    """The catalog function of another category most like the label."""


def part_functions(obj: AssemblyObject) -> dict[str, set[str]]:
    """Return part id -> the catalog functions of the requirements whose fits join that part."""
    found: dict[str, set[str]] = {}
    for requirement in obj.mechanism:
        label = requirement.function or requirement.says
        for fit_id in requirement.any_of:
            fit = obj.fit(fit_id)
            for part in (fit.moving_part, fit.fixed_part):
                found.setdefault(part, set()).add(label)
    return found


class MappingPlausibility:
    """Scores mappings onto the catalog's objects (``threshold``: below it, implausible)."""

    def __init__(self, catalog: Catalog, threshold: float = THRESHOLD) -> None:
        self.catalog = catalog
        self.threshold = threshold
        self._functions = {obj.id: part_functions(obj) for obj in catalog.objects.values()}
        same: dict[str, set[str]] = {}
        for obj in catalog.objects.values():
            same.setdefault(obj.category, set()).update(*self._functions[obj.id].values())
        # Per category, worked out once rather than for every scored pair.
        self._same_category = same
        self._other_category = {
            category: {label for other, labels in same.items() if other != category for label in labels}
            for category in same
        }

    def pair(self, test_object: str, part: str, label: str) -> PairScore:
        """Return the score of ``label`` given to ``part`` of ``test_object``."""
        category = self.catalog.get(test_object).category
        own = self._functions.get(test_object, {}).get(part, set())
        same_label, same = _nearest(label, own | self._same_category[category])
        other_label, other = _nearest(label, self._other_category[category])
        score = same / (same + other) if same + other > 0 else 0.5
        return PairScore(part, label, round(score, 4), same_label, other_label)

    def pairs(self, test_object: str, mapping: Mapping[str, Any]) -> list[PairScore]:
        """Return the score of every (part, function) of a step-3 mapping (``{"functions": {part: [labels]}}``)."""
        functions = mapping.get("functions", mapping) if isinstance(mapping, Mapping) else {}
        return [
            self.pair(test_object, str(part), str(label))
            for part, labels in (functions or {}).items()
            for label in (labels if isinstance(labels, list) else [labels])
            if str(label).strip()
        ]

    def __call__(self, test_object: str, mapping: Mapping[str, Any]) -> float:
        """Return the mapping's score: its lowest pair's (1.0 for a mapping that gives no function)."""
        return min((found.score for found in self.pairs(test_object, mapping)), default=1.0)


def _nearest(label: str, candidates: set[str]) -> tuple[str, float]:
    """Return the candidate most like ``label`` and how alike ("", 0.0 when there are none)."""
    scored = [(word_similarity(label.casefold(), candidate.casefold()), candidate) for candidate in sorted(candidates)]
    if not scored:
        return "", 0.0
    alike, best = max(scored)
    return best, alike
