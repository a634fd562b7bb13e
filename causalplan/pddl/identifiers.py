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
    """Return a PDDL predicate name for every node label: one name per label in Unicode NFC.

    Keys that differ only in how their characters are composed (NFC "café" and NFD "café")
    look the same to a person, so they get the same name; any other two keys get distinct ones.
    """
    by_form: dict[str, list[str]] = {}
    for key in set(keys):
        by_form.setdefault(unicodedata.normalize("NFC", key), []).append(key)
    result: dict[str, str] = {}
    taken: set[str] = set()
    for form in sorted(by_form):
        base = NODE_PREFIX + (slug(form) or "label")
        name, counter = base, 1
        while name in taken:
            counter += 1
            name = f"{base}-{counter}"
        taken.add(name)
        result.update(dict.fromkeys(by_form[form], name))
    return result


def comment(text: str) -> str:
    """Return ``text`` safe to place after ``;`` on one line (no line breaks, printable only)."""
    return "".join(char if char.isprintable() else " " for char in text)
