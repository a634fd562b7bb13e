"""Label alignment on the labelled paraphrase set: precision and recall by word model, weight, threshold.

    python benchmarks/alignment.py [--set tests/data/paraphrases.yaml] [--minilm FOLDER]

Each object's labels are aligned on their own (a crowd shares one training object). A pair of
labels is a true match when both have the same meaning; precision and recall count pairs.
Word measures: ``shipped`` (what the consensus uses: the larger of the next two), ``static``
(tokenlearn-static-model cosine), ``difflib`` (character overlap, no model) and ``none`` (parts
only). The part a label sits on weighs 1 - weight. Prints the best threshold per measure and
weight, then every threshold at weight 0.5 (words and part alike).
"""

from __future__ import annotations

import argparse
import difflib
from collections.abc import Callable
from pathlib import Path

import yaml

from causalplan.consensus.alignment import LabelUse, cluster_uses, pair_counts, word_similarity
from causalplan.consensus.embedding import text_similarity

ROOT = Path(__file__).resolve().parent.parent
WORD_MODELS: dict[str, Callable[[str, str], float]] = {
    "shipped": word_similarity,
    "static": text_similarity,
    "difflib": lambda a, b: difflib.SequenceMatcher(None, a, b).ratio(),
    "none": lambda a, b: 0.0,
}


def read_set(path: Path) -> dict[str, tuple[list[LabelUse], list[str]]]:
    """Return, per object, its labels as uses (held by who wrote them) and their meanings."""
    per_object: dict[str, tuple[list[LabelUse], list[str]]] = {}
    for group in yaml.safe_load(path.read_text(encoding="utf-8")):
        uses, meanings = per_object.setdefault(group["object"], ([], []))
        for item in group["labels"]:
            key = " ".join(item["label"].split()).casefold()
            person = item.get("person", f"alone-{len(uses)}")
            uses.append(LabelUse(key, item["label"], frozenset(item["parts"]), frozenset({person})))
            meanings.append(group["meaning"])
    return per_object


def score(
    per_object: dict[str, tuple[list[LabelUse], list[str]]],
    words: Callable[[str, str], float],
    weight: float,
    threshold: float,
) -> tuple[float, float]:
    """Return precision and recall over all objects' pairs (pairs pooled)."""
    true_positive = predicted = actual = 0
    for uses, meanings in per_object.values():
        counts = pair_counts(cluster_uses(uses, threshold, weight, words), meanings)
        true_positive, predicted, actual = true_positive + counts[0], predicted + counts[1], actual + counts[2]
    return (true_positive / predicted if predicted else 1.0), (true_positive / actual if actual else 1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", type=Path, default=ROOT / "tests" / "data" / "paraphrases.yaml")
    parser.add_argument(
        "--minilm",
        type=Path,
        help="also measure all-MiniLM-L6-v2 from this folder (model.safetensors, tokenizer.json; see minilm_numpy.py)",
    )
    args = parser.parse_args()
    if args.minilm:
        from minilm_numpy import MiniLM

        minilm = MiniLM(args.minilm)
        WORD_MODELS["minilm"] = minilm.similarity
        WORD_MODELS["minilm+difflib"] = lambda a, b: max(minilm.similarity(a, b), WORD_MODELS["difflib"](a, b))
    per_object = read_set(args.set)
    count = sum(len(uses) for uses, _ in per_object.values())
    print(f"{count} labels on {len(per_object)} objects from {args.set}")
    print(f"{'words':8} {'weight':>6} {'threshold':>9} {'precision':>9} {'recall':>7} {'F1':>6}")
    best: dict[tuple[str, float], tuple[float, float, float, float]] = {}
    for name, words in WORD_MODELS.items():
        for weight in (0.0, 0.25, 0.5, 0.75, 1.0):
            if name == "none" and weight > 0:
                continue
            for step in range(30, 91, 5):
                threshold = step / 100
                precision, recall = score(per_object, words, weight, threshold)
                f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
                if f1 > best.get((name, weight), (0.0, 0.0, 0.0, -1.0))[3]:
                    best[(name, weight)] = (threshold, precision, recall, f1)
    for (name, weight), (threshold, precision, recall, f1) in best.items():
        print(f"{name:8} {weight:6.2f} {threshold:9.2f} {precision:9.3f} {recall:7.3f} {f1:6.3f}")
    print("\nweight 0.50, precision/recall by threshold")
    for name, words in WORD_MODELS.items():
        cells = []
        for step in range(40, 71, 5):
            precision, recall = score(per_object, words, 0.5, step / 100)
            cells.append(f"{step / 100:.2f} {precision:.2f}/{recall:.2f}")
        print(f"{name:8} " + "  ".join(cells))


if __name__ == "__main__":
    main()
