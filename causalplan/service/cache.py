"""Answers kept for identical requests: a bounded LRU map, keyed by a request's canonical form."""

from __future__ import annotations

import copy
import hashlib
import json
import threading
from collections import OrderedDict
from typing import Any

from causalplan.causal.labels import display_label
from causalplan.causal.model import CausalModel, Labelling


class ResultCache:
    """A bounded least-recently-used map from a request's canonical key to its answer."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._entries: OrderedDict[str, dict[str, Any]] = OrderedDict()
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    def get(self, key: str) -> dict[str, Any] | None:
        """Return a copy of the answer stored for ``key``, or None."""
        with self._lock:
            entry = self._entries.get(key)
            if entry is None:
                self.misses += 1
                return None
            self._entries.move_to_end(key)
            self.hits += 1
            return copy.deepcopy(entry)

    def put(self, key: str, value: dict[str, Any]) -> None:
        """Store a copy of ``value`` for ``key``, dropping the least recently used beyond ``size``."""
        if self.size <= 0:
            return
        with self._lock:
            self._entries[key] = copy.deepcopy(value)
            self._entries.move_to_end(key)
            while len(self._entries) > self.size:
                self._entries.popitem(last=False)

    def stats(self) -> dict[str, int]:
        """Return the size, entries, hits and misses."""
        with self._lock:
            return {"size": self.size, "entries": len(self._entries), "hits": self.hits, "misses": self.misses}


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
    """Return a model in a canonical form: whitespace, part order, label order and rule order do not matter.

    Case is kept, because answers quote the labels as written.
    """
    rules = sorted(
        " AND ".join(sorted({display_label(cause) for cause in rule.causes})) + " CAUSES " + display_label(rule.effect)
        for rule in model.rules
    )
    return {**canonical_labelling(model.labelling), "goal": display_label(model.goal), "rules": rules}


def request_key(kind: str, model: CausalModel, mapping: Labelling | None, planner: str) -> str:
    """Return the cache key of a plan or transfer request: a hash of its canonical form."""
    canonical = {
        "kind": kind,
        "model": canonical_model(model),
        "mapping": canonical_labelling(mapping) if mapping is not None else None,
        "planner": planner,
    }
    return hashlib.sha256(json.dumps(canonical, sort_keys=True, ensure_ascii=False).encode()).hexdigest()
