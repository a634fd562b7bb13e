"""Near or far: how a test object stands to the objects a model was made from (the paper's two kinds of transfer)."""

from __future__ import annotations

from collections.abc import Iterable


def near_or_far(trained_categories: Iterable[str], test_category: str) -> str:
    """Return ``near`` when the test object's category is one a training object has, else ``far``."""
    return "near" if test_category in set(trained_categories) else "far"
