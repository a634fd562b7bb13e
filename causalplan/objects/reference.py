"""The expert's model of an object: its true mechanism written as a causal model (the gold standard).

Each requirement of the mechanism becomes one function, carried by the part that each of its
fits attaches (several fits: several parts carry it, and any one of them will do, as in the
mechanism); one rule says that all these functions together cause the goal. The same labels
on the same parts are the step-3 mapping that tries the model on the object itself.
"""

from __future__ import annotations

from causalplan.causal.rules import RULE_KEYWORD
from causalplan.objects.model import AssemblyObject, Requirement

_WORDS_FOR_KEYWORDS = {"and": "plus", "causes": "brings about"}


def _label(requirement: Requirement) -> str:
    """Return the requirement's function label: the expert's, else its sentence without rule keywords."""
    if requirement.function is not None:
        return requirement.function
    return RULE_KEYWORD.sub(lambda match: _WORDS_FOR_KEYWORDS[match.group(1).lower()], requirement.says)


def _functions(obj: AssemblyObject) -> list[tuple[str, tuple[str, ...]]]:
    """Return each requirement's function label with the parts that carry it, in mechanism order."""
    found: list[tuple[str, tuple[str, ...]]] = []
    used: set[str] = set()
    for number, requirement in enumerate(obj.mechanism, start=1):
        label = _label(requirement)
        if label.casefold() in used:  # two requirements worded alike must stay two functions
            label = f"{label} ({number})"
        used.add(label.casefold())
        parts = tuple(dict.fromkeys(obj.fit(fit_id).moving_part for fit_id in requirement.any_of))
        found.append((label, parts))
    return found


def reference_functions(obj: AssemblyObject) -> dict[str, list[str]]:
    """Return part id -> the function labels it carries in the object's reference model."""
    functions: dict[str, list[str]] = {}
    for label, parts in _functions(obj):
        for part in parts:
            functions.setdefault(part, []).append(label)
    return functions


def reference_model(obj: AssemblyObject) -> dict[str, object]:
    """Return the reference model of ``obj`` as a model document (what a model file holds)."""
    labels = [label for label, _ in _functions(obj)]
    return {
        "object": obj.id,
        "goal": obj.goal,
        "functions": reference_functions(obj),
        "rules": [" AND ".join(labels) + f" CAUSES {obj.goal}"],
    }


def reference_mapping(obj: AssemblyObject) -> dict[str, object]:
    """Return the step-3 mapping that tries the reference model on the object itself."""
    return {"object": obj.id, "functions": reference_functions(obj)}
