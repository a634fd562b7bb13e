"""Canonical forms of a model and a step-3 mapping: equal for documents that differ only in layout.

Whitespace, part, label and rule order do not matter; case does (answers quote the labels as
written). The service keys its kept answers by these texts and stores a model's hash with it.
"""

from __future__ import annotations

import hashlib
import json

from causalplan.causal.labels import display_label
from causalplan.causal.model import CausalModel, Labelling


def canonical_labelling(labelling: Labelling) -> dict[str, object]:
    """Return a labelling in a canonical form: parts sorted, each part's labels sorted."""
    return {
        "object": labelling.object_id,
        "functions": {
            part: sorted({display_label(label) for label in labels})
            for part, labels in sorted(labelling.functions.items())
            if labels
        },
    }


def canonical_model(model: CausalModel) -> dict[str, object]:
    """Return a model in a canonical form: whitespace, part, label and rule order do not matter."""
    rules = sorted(
        " AND ".join(sorted({display_label(cause) for cause in rule.causes})) + " CAUSES " + display_label(rule.effect)
        for rule in model.rules
    )
    return {**canonical_labelling(model.labelling), "goal": display_label(model.goal), "rules": rules}


def canonical_text(value: dict[str, object] | None) -> str:
    """Return the canonical JSON text of a canonical form (keys sorted, text as written)."""
    return json.dumps(value, sort_keys=True, ensure_ascii=False)


def model_text(model: CausalModel) -> str:
    """Return the model's canonical text: equal for models that differ only in layout."""
    return canonical_text(canonical_model(model))


def mapping_text(mapping: Labelling | None) -> str:
    """Return the canonical text of a step-3 mapping (of no mapping too)."""
    return canonical_text(canonical_labelling(mapping) if mapping is not None else None)


def model_hash(model: CausalModel) -> str:
    """Return the hash of the model's canonical form (equal for models that differ only in layout)."""
    return hashlib.sha256(model_text(model).encode("utf-8", "replace")).hexdigest()
