"""Function and effect labels: free text chosen by people, compared after normalisation."""

from __future__ import annotations

import difflib
import unicodedata


def normalize_label(label: str) -> str:
    """Return the label's comparison key: Unicode NFC, case folded, whitespace collapsed (nothing else).

    NFC first, so "café" typed as one character or as "e" and a combining accent is one label;
    again after folding, which can take a character apart (e.g. "ǰ").
    """
    return unicodedata.normalize("NFC", unicodedata.normalize("NFC", " ".join(label.split())).casefold())


def display_label(label: str) -> str:
    """Return the label as people wrote it in Unicode NFC, with runs of whitespace collapsed to one space."""
    return unicodedata.normalize("NFC", " ".join(label.split()))


def has_control_characters(label: str) -> bool:
    """Return whether the label holds characters that are neither printable nor whitespace."""
    if label.isprintable():  # in C: no character of the categories below is printable
        return False
    return any(unicodedata.category(char) in {"Cc", "Cf", "Cs", "Co"} and not char.isspace() for char in label)


def closest(word: str, candidates: list[str], cutoff: float = 0.6) -> str | None:
    """Return the candidate most similar to ``word``, or None when none is close."""
    matches = difflib.get_close_matches(word, candidates, n=1, cutoff=cutoff)
    return matches[0] if matches else None
