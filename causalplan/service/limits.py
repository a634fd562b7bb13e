"""The service's limits on a submitted model or mapping, checked before anything reads it.

The model reader checks meaning and reports with the CLI's codes; these checks only bound
the work one request can cause (parts, labels, rules, nesting) and make the document safe
to store in any database (no NaN, no NUL, no unpaired surrogates).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any

from causalplan.service.errors import InvalidRequestError, LimitExceededError
from causalplan.service.settings import Settings

MAX_NESTING = 16
"""A model needs three levels (document, functions, labels); anything deeper is refused."""

RULE_LENGTH_FACTOR = 4
"""A rule may be this many labels long (as in ``causalplan.causal.model``)."""


def clean_text(text: str) -> str:
    """Return ``text`` with NUL and unpaired surrogates replaced by U+FFFD (storable everywhere)."""
    if text.isascii() and "\x00" not in text:
        return text
    return "".join("\ufffd" if char == "\x00" or "\ud800" <= char <= "\udfff" else char for char in text)


def clean_json(value: object, what: str = "the document") -> Any:
    """Return a copy of parsed JSON with every string cleaned; refuse NaN, infinities and deep nesting."""

    def clean(item: object, depth: int) -> Any:
        if depth > MAX_NESTING:
            raise InvalidRequestError(
                f"{what.capitalize()} is nested more than {MAX_NESTING} levels deep.",
                details={"limit": MAX_NESTING},
            )
        if isinstance(item, str):
            return clean_text(item)
        if isinstance(item, float) and not math.isfinite(item):
            raise InvalidRequestError(f"{what.capitalize()} contains {json.dumps(item)}, which JSON does not allow.")
        if isinstance(item, Mapping):
            return {clean_text(str(key)): clean(child, depth + 1) for key, child in item.items()}
        if isinstance(item, list):
            return [clean(child, depth + 1) for child in item]
        return item

    return clean(value, 0)


def _too_long(settings: Settings, label: object) -> bool:
    return isinstance(label, str) and len(label) > settings.max_label_length


def check_labelling_limits(document: Mapping[str, Any], settings: Settings, what: str) -> None:
    """Raise LimitExceededError when a model's or mapping's ``functions`` are over the limits."""
    functions = document.get("functions")
    if not isinstance(functions, Mapping):
        return  # the reader reports the wrong type with its own code
    if len(functions) > settings.max_parts:
        raise LimitExceededError(
            "too_many_parts",
            f"The {what} labels {len(functions)} parts; the limit is {settings.max_parts}.",
            details={"limit": settings.max_parts, "actual": len(functions), "field": "functions"},
        )
    for part, labels in functions.items():
        items = labels if isinstance(labels, list) else [labels]
        if len(items) > settings.max_labels_per_part:
            raise LimitExceededError(
                "too_many_labels",
                f"Part '{part}' of the {what} has {len(items)} function labels; the limit is "
                f"{settings.max_labels_per_part}.",
                details={"limit": settings.max_labels_per_part, "actual": len(items), "part": str(part)},
            )
        for label in items:
            if _too_long(settings, label):
                raise LimitExceededError(
                    "label_too_long",
                    f"A function label of part '{part}' is {len(label)} characters long; the limit is "
                    f"{settings.max_label_length}.",
                    details={"limit": settings.max_label_length, "actual": len(label), "part": str(part)},
                )


def check_model_limits(document: Mapping[str, Any], settings: Settings) -> None:
    """Raise LimitExceededError when a model document is over the service's limits."""
    check_labelling_limits(document, settings, "model")
    goal = document.get("goal")
    if isinstance(goal, str) and _too_long(settings, goal):
        raise LimitExceededError(
            "label_too_long",
            f"The goal is {len(goal)} characters long; the limit is {settings.max_label_length}.",
            details={"limit": settings.max_label_length, "actual": len(goal), "field": "goal"},
        )
    rules = document.get("rules")
    if isinstance(rules, str):
        rules = [line for line in rules.splitlines() if line.strip()]
    if not isinstance(rules, list):
        return
    if len(rules) > settings.max_rules:
        raise LimitExceededError(
            "too_many_rules",
            f"The model has {len(rules)} rules; the limit is {settings.max_rules}.",
            details={"limit": settings.max_rules, "actual": len(rules), "field": "rules"},
        )
    longest = RULE_LENGTH_FACTOR * settings.max_label_length
    for index, rule in enumerate(rules, start=1):
        if isinstance(rule, str) and len(rule) > longest:
            raise LimitExceededError(
                "label_too_long",
                f"Rule {index} is {len(rule)} characters long; the limit is {longest}.",
                details={"limit": longest, "actual": len(rule), "rule": index},
            )
