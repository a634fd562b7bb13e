"""Safe PDDL identifiers for labels written by people.

A label can hold anything (``x) (:action evil``); its identifier holds only lower-case ASCII
letters, digits and hyphens behind a fixed prefix, so it can never change the PDDL's
structure. Labels that collide after sanitising get numbered suffixes, assigned in sorted
order of the labels so the same model always compiles to the same text.
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterable

NODE_PREFIX = "n-"
MAX_SLUG_LENGTH = 48
_NOT_SLUG = re.compile(r"[^a-z0-9]+")


def slug(label: str) -> str:
    """Return ``label`` reduced to lower-case ASCII words joined by hyphens (maybe empty)."""
    ascii_text = unicodedata.normalize("NFKD", label).encode("ascii", "ignore").decode("ascii").lower()
    return _NOT_SLUG.sub("-", ascii_text).strip("-")[:MAX_SLUG_LENGTH].strip("-")


def node_identifiers(keys: Iterable[str]) -> dict[str, str]:
    """Return a distinct PDDL predicate name for every normalised node label."""
    result: dict[str, str] = {}
    taken: set[str] = set()
    for key in sorted(set(keys)):
        base = NODE_PREFIX + (slug(key) or "label")
        name, counter = base, 1
        while name in taken:
            counter += 1
            name = f"{base}-{counter}"
        taken.add(name)
        result[key] = name
    return result


def comment(text: str) -> str:
    """Return ``text`` safe to place after ``;`` on one line (no line breaks, printable only)."""
    return "".join(char if char.isprintable() else " " for char in text)
