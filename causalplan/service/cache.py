"""Kept work for repeated requests: bounded LRU maps, keyed by a request's canonical form.

Two levels, each bounded by ``cache_size`` entries and by ``MAX_BYTES`` (an entry weighs what
it was made from). ``Services.reads`` keeps what reading a model or mapping document gave, keyed
by the document's exact JSON: an identical document is neither read nor validated again (the
values are frozen, so they are shared, not copied). ``ResultCache`` keeps planners' answers,
keyed by the canonical form of everything an answer depends on: the kind of answer, model,
mapping, planner, time limit and catalog.
"""

from __future__ import annotations

import hashlib
import json
import pickle
import threading
from collections import OrderedDict
from typing import Any, Generic, TypeVar

from causalplan.causal.labels import display_label
from causalplan.causal.model import CausalModel, Labelling
from causalplan.objects.catalog import Catalog

V = TypeVar("V")


MAX_BYTES = 64 * 1024 * 1024
"""The most one cache holds, measured as the size of what its entries were made from."""


class LruCache(Generic[V]):
    """A bounded least-recently-used map from a key to a value.

    Bounded twice: at most ``size`` entries (0 keeps nothing), and at most ``max_bytes`` in all,
    each entry weighing what the caller says it does (an answer's pickled size, a document's JSON).
    """

    def __init__(self, size: int, max_bytes: int = MAX_BYTES) -> None:
        self.size = size
        self.max_bytes = max_bytes
        self._entries: OrderedDict[str, tuple[V, int]] = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    def get(self, key: str) -> V | None:
        """Return the value stored for ``key``, or None."""
        with self._lock:
            entry = self._entries.get(key)
            if entry is None:
                self.misses += 1
                return None
            self._entries.move_to_end(key)
            self.hits += 1
            return entry[0]

    def put(self, key: str, value: V, weight: int = 0) -> None:
        """Store ``value`` for ``key``, dropping the least recently used beyond the bounds."""
        if self.size <= 0 or weight > self.max_bytes:
            return
        with self._lock:
            previous = self._entries.pop(key, None)
            if previous is not None:
                self._bytes -= previous[1]
            self._entries[key] = (value, weight)
            self._bytes += weight
            while len(self._entries) > self.size or self._bytes > self.max_bytes:
                _, (_, dropped) = self._entries.popitem(last=False)
                self._bytes -= dropped

    def __len__(self) -> int:
        with self._lock:
            return len(self._entries)

    @property
    def bytes(self) -> int:
        """Return the weight of every entry together."""
        with self._lock:
            return self._bytes

    def stats(self) -> dict[str, int]:
        """Return the size, entries, hits and misses."""
        with self._lock:
            return {"size": self.size, "entries": len(self._entries), "hits": self.hits, "misses": self.misses}


class ResultCache:
    """Planners' answers by request key, kept pickled: each ``get`` returns a fresh copy.

    So no caller can change what another gets; unpickling costs a quarter of a deep copy, and
    the pickle's length is the entry's weight.
    """

    def __init__(self, size: int, max_bytes: int = MAX_BYTES) -> None:
        self._pickles: LruCache[bytes] = LruCache(size, max_bytes)

    @property
    def size(self) -> int:
        return self._pickles.size

    def get(self, key: str) -> dict[str, Any] | None:
        """Return a copy of the answer stored for ``key``, or None."""
        data = self._pickles.get(key)
        if data is None:
            return None
        answer: dict[str, Any] = pickle.loads(data)  # our own bytes, never a client's
        return answer

    def put(self, key: str, value: dict[str, Any]) -> None:
        """Store a copy of ``value`` for ``key``."""
        if self._pickles.size > 0:
            data = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
            self._pickles.put(key, data, len(data))

    def __len__(self) -> int:
        return len(self._pickles)

    def stats(self) -> dict[str, int]:
        """Return the size, entries, hits and misses."""
        return self._pickles.stats()


def document_key(kind: str, document: object) -> tuple[str, int]:
    """Return the key of a submitted document, a hash of its exact JSON (key order and all), and the JSON's size.

    Exact, not canonical: the reader's report and the stored copy follow the document as sent.
    """
    text = json.dumps([kind, document], ensure_ascii=True, allow_nan=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest(), len(text)


def catalog_key(catalog: Catalog) -> str:
    """Return a fingerprint of the catalog's objects (computed once, when the service starts)."""
    text = repr(sorted(catalog.objects.items()))
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


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


def canonical_text(value: dict[str, object] | None) -> str:
    """Return the canonical JSON text of a canonical form (keys sorted, text as written)."""
    return json.dumps(value, sort_keys=True, ensure_ascii=False)


def answer_key(kind: str, model_text: str, mapping_text: str, planner: str, time_limit: float, catalog: str) -> str:
    """Return the cache key of an answer from the canonical texts of its model and mapping.

    Everything an answer depends on is in it: the kind of answer, the model, the mapping, the
    planner, the time limit (a time limit can change which planner answers) and the catalog.
    """
    text = json.dumps([kind, model_text, mapping_text, planner, float(time_limit), catalog], ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


def request_key(
    kind: str, model: CausalModel, mapping: Labelling | None, planner: str, time_limit: float, catalog: str
) -> str:
    """Return the cache key of a plan, transfer or simulation request: a hash of its canonical form."""
    mapping_text = canonical_text(canonical_labelling(mapping) if mapping is not None else None)
    return answer_key(kind, canonical_text(canonical_model(model)), mapping_text, planner, time_limit, catalog)
