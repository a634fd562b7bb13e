"""Function and effect labels: free text chosen by people, compared after normalisation."""

from __future__ import annotations

import difflib
import unicodedata


def normalize_label(label: str) -> str:
    """Return the label's comparison key: case folded, whitespace collapsed (nothing else)."""
    return " ".join(label.split()).casefold()


def display_label(label: str) -> str:
    """Return the label as people wrote it, with runs of whitespace collapsed to one space."""
    return " ".join(label.split())


def has_control_characters(label: str) -> bool:
    """Return whether the label holds characters that are neither printable nor whitespace."""
    if label.isprintable():  # in C: no character of the categories below is printable
        return False
    return any(unicodedata.category(char) in {"Cc", "Cf", "Cs", "Co"} and not char.isspace() for char in label)


def closest(word: str, candidates: list[str], cutoff: float = 0.6) -> str | None:
    """Return the candidate most similar to ``word``, or None when none is close."""
    matches = difflib.get_close_matches(word, candidates, n=1, cutoff=cutoff)
    return matches[0] if matches else None
