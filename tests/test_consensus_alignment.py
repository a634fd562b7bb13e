"""Label alignment: paraphrases on the same part become one node; different meanings stay apart."""

from __future__ import annotations

from pathlib import Path

import yaml

from causalplan.consensus.alignment import LabelUse, cluster_uses, jaccard, pair_precision_recall, similarity

PARAPHRASES = Path(__file__).resolve().parent / "data" / "paraphrases.yaml"
# Measured on the set with the shipped threshold and weights (benchmarks/alignment.py):
# precision 0.968, recall 0.891. The floors leave room for nothing but a real regression.
PRECISION_FLOOR, RECALL_FLOOR = 0.95, 0.85


def _use(label: str, parts: list[str], person: str) -> LabelUse:
    return LabelUse(label, label, frozenset(parts), frozenset({person}))


def _labelled_set() -> dict[str, tuple[list[LabelUse], list[str]]]:
    per_object: dict[str, tuple[list[LabelUse], list[str]]] = {}
    for group in yaml.safe_load(PARAPHRASES.read_text(encoding="utf-8")):
        uses, meanings = per_object.setdefault(group["object"], ([], []))
        for item in group["labels"]:
            uses.append(_use(item["label"], item["parts"], item.get("person", f"alone-{len(uses)}")))
            meanings.append(group["meaning"])
    return per_object


def test_alignment_on_the_labelled_paraphrase_set_is_above_the_measured_floor() -> None:
    true_positive = predicted = actual = 0.0
    for uses, meanings in _labelled_set().values():
        groups = cluster_uses(uses)
        precision, _recall = pair_precision_recall(groups, meanings)
        group_of = {index: number for number, group in enumerate(groups) for index in group}
        pairs = [(i, j) for i in range(len(uses)) for j in range(i + 1, len(uses))]
        same_group = sum(group_of[i] == group_of[j] for i, j in pairs)
        true_positive += precision * same_group
        predicted += same_group
        actual += sum(meanings[i] == meanings[j] for i, j in pairs)
    assert true_positive / predicted >= PRECISION_FLOOR
    assert true_positive / actual >= RECALL_FLOOR


def test_the_part_weighs_as_much_as_the_words() -> None:
    same_words_other_part = similarity(_use("glow", ["shade"], "a"), _use("glow", ["light_bulb"], "b"))
    other_words_same_part = similarity(_use("glow", ["light_bulb"], "a"), _use("close the circuit", ["light_bulb"], "b"))
    assert same_words_other_part == 0.5
    assert 0.5 <= other_words_same_part < 0.51


def test_supply_power_and_provide_electricity_on_one_part_are_one_node() -> None:
    uses = [_use("provide electricity", ["base"], "a"), _use("supply power", ["base"], "b")]
    assert cluster_uses(uses) == [[0, 1]]


def test_one_persons_two_labels_are_never_one_node() -> None:
    uses = [_use("glow", ["light_bulb"], "a"), _use("close the circuit", ["light_bulb"], "a"), _use("glow", ["light_bulb"], "b")]
    assert cluster_uses(uses) == [[0, 2], [1]]


def test_jaccard_of_two_empty_contexts_is_one() -> None:
    assert jaccard(frozenset(), frozenset()) == 1.0
    assert jaccard(frozenset({"a"}), frozenset({"a", "b"})) == 0.5


def test_pair_precision_and_recall_count_pairs() -> None:
    # Truth: {0, 1} and {2}; prediction puts all three together: 1 of 3 pairs right, the one true pair found.
    assert pair_precision_recall([[0, 1, 2]], ["x", "x", "y"]) == (1 / 3, 1.0)
    assert pair_precision_recall([[0], [1], [2]], ["x", "x", "y"]) == (1.0, 0.0)
