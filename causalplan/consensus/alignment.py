"""Label alignment: labels that mean the same across people become one node of the consensus.

Two labels are alike by their words and by where they sit:
for a function, the parts that carry it; for an intermediate effect, the aligned nodes that
cause it. Words are alike by the larger of two measures: the cosine of static sentence
embeddings (synonyms that share no letters) and difflib's character overlap (spelling
variants and words outside the embedding's 10k-token vocabulary). Both halves weigh the same
(``TEXT_WEIGHT`` 0.5), because words alone mislead:
"supply power" and "provide electricity" are far apart in words yet sit on the same part.
Labels are grouped by average linkage, never putting two different labels of one person into
one node (a person who wrote two labels meant two things). Hand-written: scipy's hierarchical
clustering has no such cannot-link constraint.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np

from causalplan.consensus.embedding import text_similarity

TEXT_WEIGHT = 0.5
"""The share of a label's words in its similarity; the rest is where it sits (parts, causes)."""
THRESHOLD = 0.55
"""Labels at least this alike (on average, group to group) are one node. Chosen on
tests/data/paraphrases.yaml by benchmarks/alignment.py (figures in benchmarks/RESULTS.md)."""


@dataclass(frozen=True)
class LabelUse:
    """One way a label was used: its key, as written, where it sits, and who used it so."""

    key: str
    text: str
    context: frozenset[str]
    holders: frozenset[str]


def jaccard(first: frozenset[str], second: frozenset[str]) -> float:
    """Return |A & B| / |A | B| (1.0 for two empty sets: nothing tells them apart)."""
    union = first | second
    return len(first & second) / len(union) if union else 1.0


WordSimilarity = Callable[[str, str], float]


def word_similarity(first: str, second: str) -> float:
    """Return how alike two labels' words are, in [0, 1]: embedding cosine or character overlap, the larger."""
    return max(text_similarity(first, second), difflib.SequenceMatcher(None, first, second).ratio())


def similarity(
    first: LabelUse, second: LabelUse, text_weight: float = TEXT_WEIGHT, words: WordSimilarity = word_similarity
) -> float:
    """Return how alike two label uses are, in [0, 1]: words and context, weighted."""
    alike = words(first.key, second.key)
    return text_weight * alike + (1.0 - text_weight) * jaccard(first.context, second.context)


def cluster_uses(
    uses: Sequence[LabelUse],
    threshold: float = THRESHOLD,
    text_weight: float = TEXT_WEIGHT,
    words: WordSimilarity = word_similarity,
) -> list[list[int]]:
    """Return groups of indices into ``uses`` that mean the same, each sorted, groups by first index.

    Average linkage weighted by how many people used each label; two groups never merge when
    one person used different labels in each.
    """
    count = len(uses)
    mass = np.array([max(1, len(use.holders)) for use in uses], dtype=np.float64)
    linkage = np.eye(count)
    for i, j in combinations(range(count), 2):
        linkage[i, j] = linkage[j, i] = similarity(uses[i], uses[j], text_weight, words)
    holders = [use.holders for use in uses]
    apart = np.array([[bool(a & b) for b in holders] for a in holders]).reshape(count, count)
    np.fill_diagonal(apart, True)
    groups: dict[int, list[int]] = {index: [index] for index in range(count)}
    while len(groups) > 1:
        # Average linkage, updated in place (Lance-Williams): a merged group's row is the
        # mass-weighted mean of its two rows; pairs that share a person stay apart.
        candidates = np.where(apart, -np.inf, linkage)
        row, column = (int(index) for index in np.unravel_index(int(np.argmax(candidates)), candidates.shape))
        if candidates[row, column] < threshold:
            break
        a, b = min(row, column), max(row, column)
        merged = (mass[a] * linkage[a] + mass[b] * linkage[b]) / (mass[a] + mass[b])
        linkage[a, :] = linkage[:, a] = merged
        apart[a, :] = apart[:, a] = apart[a] | apart[b]
        apart[b, :] = apart[:, b] = True
        mass[a] += mass[b]
        groups[a] = sorted(groups[a] + groups.pop(b))
    return sorted(groups.values(), key=lambda group: group[0])


def pair_counts(groups: Sequence[Sequence[int]], meanings: Sequence[str]) -> tuple[int, int, int]:
    """Return the pairs grouped together that mean the same, the pairs grouped, the pairs that mean the same."""
    group_of = {index: number for number, group in enumerate(groups) for index in group}
    true_positive = predicted = actual = 0
    for i, j in combinations(range(len(meanings)), 2):
        same_group, same_meaning = group_of[i] == group_of[j], meanings[i] == meanings[j]
        predicted += same_group
        actual += same_meaning
        true_positive += same_group and same_meaning
    return true_positive, predicted, actual


def pair_precision_recall(groups: Sequence[Sequence[int]], meanings: Sequence[str]) -> tuple[float, float]:
    """Return the precision and recall of "same group" over all pairs, against the true meanings."""
    true_positive, predicted, actual = pair_counts(groups, meanings)
    return (true_positive / predicted if predicted else 1.0), (true_positive / actual if actual else 1.0)
