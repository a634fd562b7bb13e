"""The limits that bound the work one document can cause: parts, labels per part, label and rule length, rules.

The service checks a request's model or mapping against them before reading it, and a
study checks a participant's; ``Settings`` holds the numbers.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from causalplan.errors import CausalPlanError
from causalplan.settings import Settings

RULE_LENGTH_FACTOR = 4
"""A rule may be this many labels long (as in ``causalplan.causal.model``)."""


class LimitExceededError(CausalPlanError):
    """A request is over one of the service's limits (parts, rules, label length, time limit)."""

    code = "limit_exceeded"

    def __init__(self, code: str, message: str, *, details: dict[str, object] | None = None) -> None:
        super().__init__(message, details=details)
        self.code = code


def _too_long(settings: Settings, label: object) -> bool:
    return isinstance(label, str) and len(label) > settings.max_label_length


def _over_limit(code: str, what_is: str, limit: int, actual: int, **where: object) -> LimitExceededError:
    """Return the error of a document over one limit: ``what_is`` says what it has, then the limit."""
    return LimitExceededError(
        code, f"{what_is}; the limit is {limit}.", details={"limit": limit, "actual": actual, **where}
    )


def check_labelling_limits(document: Mapping[str, Any], settings: Settings, what: str) -> None:
    """Raise LimitExceededError when a model's or mapping's ``functions`` are over the limits."""
    functions = document.get("functions")
    if not isinstance(functions, Mapping):
        return  # the reader reports the wrong type with its own code
    if len(functions) > settings.max_parts:
        count = len(functions)
        raise _over_limit(
            "too_many_parts", f"The {what} labels {count} parts", settings.max_parts, count, field="functions"
        )
    for part, labels in functions.items():
        items = labels if isinstance(labels, list) else [labels]
        if len(items) > settings.max_labels_per_part:
            what_is = f"Part '{part}' of the {what} has {len(items)} function labels"
            raise _over_limit("too_many_labels", what_is, settings.max_labels_per_part, len(items), part=str(part))
        for label in items:
            if _too_long(settings, label):
                what_is = f"A function label of part '{part}' is {len(label)} characters long"
                raise _over_limit("label_too_long", what_is, settings.max_label_length, len(label), part=str(part))


def check_model_limits(document: Mapping[str, Any], settings: Settings) -> None:
    """Raise LimitExceededError when a model document is over the service's limits."""
    check_labelling_limits(document, settings, "model")
    goal = document.get("goal")
    if isinstance(goal, str) and _too_long(settings, goal):
        what_is = f"The goal is {len(goal)} characters long"
        raise _over_limit("label_too_long", what_is, settings.max_label_length, len(goal), field="goal")
    rules = document.get("rules")
    if isinstance(rules, str):
        rules = [line for line in rules.splitlines() if line.strip()]
    if not isinstance(rules, list):
        return
    if len(rules) > settings.max_rules:
        count = len(rules)
        raise _over_limit("too_many_rules", f"The model has {count} rules", settings.max_rules, count, field="rules")
    longest = RULE_LENGTH_FACTOR * settings.max_label_length
    for index, rule in enumerate(rules, start=1):
        if isinstance(rule, str) and len(rule) > longest:
            what_is = f"Rule {index} is {len(rule)} characters long"
            raise _over_limit("label_too_long", what_is, longest, len(rule), rule=index)
