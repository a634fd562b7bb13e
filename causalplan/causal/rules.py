"""The step-2 rule language: ``CAUSE [AND CAUSE ...] CAUSES EFFECT``, keywords in any case.

Several rules with the same effect are alternatives (OR); the causes of one rule are all
needed (AND). Parsing never raises: it returns a rule or the diagnostics saying why not.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cached_property

from causalplan.causal.diagnostics import Diagnostic, Location, error, warning
from causalplan.causal.labels import display_label, has_control_characters, normalize_label

_CAUSES = re.compile(r"(?<!\S)causes(?!\S)", re.IGNORECASE)
_AND = re.compile(r"(?<!\S)and(?!\S)", re.IGNORECASE)
_OR = re.compile(r"(?<!\S)or(?!\S)", re.IGNORECASE)
RULE_KEYWORD = re.compile(r"(?<!\S)(and|causes)(?!\S)", re.IGNORECASE)
"""AND or CAUSES written as a word of a label (any case): a rule would read it as a keyword."""


def keywords_in(label: str) -> list[str]:
    """Return the rule keywords (AND, CAUSES) that ``label`` holds as words, upper-case, once each."""
    return sorted({match.upper() for match in RULE_KEYWORD.findall(label)})


@dataclass(frozen=True)
class Rule:
    """One causal rule: all ``causes`` together produce ``effect`` (labels as written)."""

    causes: tuple[str, ...]
    effect: str
    text: str
    index: int

    # Worked out once per rule (reading a model asks for them many times): a frozen dataclass's
    # cached_property is written to the instance's __dict__, outside its fields.
    @cached_property
    def cause_keys(self) -> frozenset[str]:
        return frozenset(normalize_label(cause) for cause in self.causes)

    @cached_property
    def effect_key(self) -> str:
        return normalize_label(self.effect)

    def canonical(self) -> str:
        """Return the rule in canonical form (normalised labels, causes sorted)."""
        return " AND ".join(sorted(self.cause_keys)) + " CAUSES " + self.effect_key


def parse_rule(text: str, index: int, location: Location) -> tuple[Rule | None, list[Diagnostic]]:
    """Parse one rule; return it (or None when it is unusable) and what was found wrong."""
    shown = display_label(text)
    if has_control_characters(text):
        return None, [
            error(
                "invalid_character",
                f"Rule {index} contains invisible control characters.",
                location,
                "Retype the rule using ordinary letters, digits and punctuation.",
            )
        ]
    if not shown:
        return None, [
            error(
                "empty_rule",
                f"Rule {index} is empty.",
                location,
                "Write it as: CAUSE AND CAUSE CAUSES EFFECT, or delete it.",
            )
        ]
    pieces = _CAUSES.split(shown)
    if len(pieces) == 1:
        return None, [
            error(
                "missing_causes_keyword",
                f"Rule {index} ('{shown}') has no CAUSES keyword.",
                location,
                "Write it as: CAUSE AND CAUSE CAUSES EFFECT, e.g. "
                "'provide electricity AND turn electricity into light CAUSES light'.",
            )
        ]
    if len(pieces) > 2:
        return None, [
            error(
                "multiple_causes_keywords",
                f"Rule {index} ('{shown}') uses CAUSES {len(pieces) - 1} times; a rule has exactly one.",
                location,
                "Split it into separate rules, e.g. 'A CAUSES B' and 'B CAUSES C'.",
            )
        ]
    cause_text, effect = pieces[0].strip(), pieces[1].strip()
    problems: list[Diagnostic] = []
    if not cause_text:
        problems.append(
            error(
                "rule_without_causes",
                f"Rule {index} ('{shown}') has nothing before CAUSES.",
                location,
                "Name at least one function or effect that causes it, e.g. "
                f"'provide electricity CAUSES {effect or 'light'}'.",
            )
        )
    if not effect:
        problems.append(
            error(
                "rule_without_effect",
                f"Rule {index} ('{shown}') has nothing after CAUSES.",
                location,
                "Name the effect the causes produce, e.g. '... CAUSES light'.",
            )
        )
    if effect and _AND.search(effect):
        problems.append(
            error(
                "multiple_effects",
                f"Rule {index} ('{shown}') has AND after CAUSES; a rule has exactly one effect.",
                location,
                "Write one rule per effect, e.g. 'A CAUSES B' and 'A CAUSES C'.",
            )
        )
    causes = [piece.strip() for piece in _AND.split(cause_text)] if cause_text else []
    if any(not cause for cause in causes):
        problems.append(
            error(
                "empty_label",
                f"Rule {index} ('{shown}') has an AND with nothing on one side.",
                location,
                "Put a function or effect on both sides of every AND.",
            )
        )
    if problems:
        return None, problems
    seen: set[str] = set()
    unique: list[str] = []
    for cause in causes:
        key = normalize_label(cause)
        if key in seen:
            problems.append(
                warning("duplicate_cause", f"Rule {index} names '{cause}' twice.", location, "Once is enough.")
            )
            continue
        seen.add(key)
        unique.append(cause)
    for label in [*unique, effect]:
        if _OR.search(label):
            problems.append(
                warning(
                    "or_in_label",
                    f"Rule {index}: '{label}' contains the word 'or', which is not a keyword.",
                    location,
                    "For alternatives write one rule per alternative with the same effect, "
                    "e.g. 'A CAUSES light' and 'B CAUSES light'.",
                )
            )
    return Rule(tuple(unique), effect, shown, index), problems
