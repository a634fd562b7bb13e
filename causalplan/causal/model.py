"""A person's causal model (steps 1 and 2) and a step-3 mapping, read from plain data.

The file contract (YAML or JSON, same schema)::

    object: desk_lamp            # catalog id of the object
    goal: light                  # optional, default "light"
    functions:                   # part id -> function labels (free text, many-to-many)
      base_with_cables: [provide electricity]
    rules:                       # keyword rules, one per entry (models only)
      - provide electricity AND turn electricity into light CAUSES light

A step-3 mapping has only ``object`` and ``functions``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from causalplan.causal.diagnostics import Diagnostic, Location, error, warning
from causalplan.causal.documents import SourceMap
from causalplan.causal.labels import closest, display_label, has_control_characters, normalize_label
from causalplan.causal.rules import Rule, keywords_in, parse_rule

DEFAULT_GOAL = "light"
MAX_LABEL_LENGTH = 200
MODEL_FIELDS = ("object", "goal", "functions", "rules")
MAPPING_FIELDS = ("object", "functions")


@dataclass(frozen=True)
class Labelling:
    """Which parts of one object carry which function labels (step 1, or step 3's mapping)."""

    object_id: str
    functions: Mapping[str, tuple[str, ...]]
    source: SourceMap = field(default_factory=SourceMap, compare=False)

    def carriers(self) -> dict[str, tuple[str, ...]]:
        """Return each normalised function label with the parts carrying it (sorted)."""
        result: dict[str, set[str]] = {}
        for part, labels in self.functions.items():
            for label in labels:
                result.setdefault(normalize_label(label), set()).add(part)
        return {key: tuple(sorted(parts)) for key, parts in sorted(result.items())}

    def labels(self) -> dict[str, str]:
        """Return each normalised function label with the first way it was written."""
        result: dict[str, str] = {}
        for labels in self.functions.values():
            for label in labels:
                result.setdefault(normalize_label(label), display_label(label))
        return result

    def as_dict(self) -> dict[str, object]:
        """Return the labelling in the file schema."""
        return {"object": self.object_id, "functions": {part: list(labels) for part, labels in self.functions.items()}}


@dataclass(frozen=True)
class CausalModel:
    """Steps 1 and 2: a labelling of the training object and rules that produce the goal."""

    labelling: Labelling
    goal: str
    rules: tuple[Rule, ...]

    @property
    def object_id(self) -> str:
        return self.labelling.object_id

    @property
    def goal_key(self) -> str:
        return normalize_label(self.goal)

    @property
    def source(self) -> SourceMap:
        return self.labelling.source

    def node_labels(self) -> dict[str, str]:
        """Return every node of the model (functions, effects, goal) with its display label."""
        return node_labels(self.labelling, self.rules, self.goal)

    def used_labels(self) -> set[str]:
        """Return the normalised labels the rules mention (causes, effects) and the goal."""
        used = {self.goal_key}
        for rule in self.rules:
            used |= rule.cause_keys
            used.add(rule.effect_key)
        return used

    def as_dict(self) -> dict[str, object]:
        """Return the model in the file schema."""
        return {**self.labelling.as_dict(), "goal": self.goal, "rules": [rule.text for rule in self.rules]}


def node_labels(labelling: Labelling, rules: tuple[Rule, ...], goal: str) -> dict[str, str]:
    """Return every node (functions carried, rule causes and effects, goal) with its label."""
    labels = labelling.labels()
    for rule in rules:
        for cause in rule.causes:
            labels.setdefault(normalize_label(cause), cause)
        labels.setdefault(rule.effect_key, rule.effect)
    labels.setdefault(normalize_label(goal), display_label(goal))
    return labels


def _check_fields(
    data: Mapping[object, object], allowed: tuple[str, ...], required: tuple[str, ...], source: SourceMap, what: str
) -> list[Diagnostic]:
    problems: list[Diagnostic] = []
    for key in data:
        if key not in allowed:
            guess = closest(str(key), list(allowed))
            hint = f"Did you mean '{guess}'?" if guess else f"A {what} has the fields: {', '.join(allowed)}."
            if what == "mapping" and key == "rules":
                hint = "A step-3 mapping cannot change the rules: the training model stays as it was."
            problems.append(
                error("unknown_field", f"The {what} has an unknown field '{key}'.", source.locate(str(key)), hint)
            )
    for name in required:
        if name not in data:
            problems.append(
                error("missing_field", f"The {what} has no '{name}' field.", source.locate(), _FIELD_HINTS[name])
            )
    return problems


_FIELD_HINTS = {
    "object": "Add the catalog id of the object, e.g. 'object: desk_lamp' (see `causalplan objects`).",
    "functions": "Add which parts carry which functions, "
    "e.g. 'functions: {light_bulb: [turn electricity into light]}'.",
    "rules": "Add rules such as 'provide electricity AND turn electricity into light CAUSES light'.",
}


def _label_problem(
    value: object, where: Location, words: Mapping[str, tuple[str, str | None]], part: str = ""
) -> Diagnostic | None:
    """Return why ``value`` cannot be a label (not text, empty, control characters, too long), or None.

    The checks are the same for a part's function and for the goal; ``words`` gives each code's
    message and hint, as templates of ``type``, ``value``, ``length`` and ``part``.
    """
    if not isinstance(value, str):
        code = "invalid_type"
    elif not value.strip():
        code = "empty_label"
    elif has_control_characters(value):
        code = "invalid_character"
    elif len(value) > MAX_LABEL_LENGTH:
        code = "label_too_long"
    else:
        return None
    message, hint = words[code]
    length = len(value) if isinstance(value, str) else 0
    return error(code, message.format(type=type(value).__name__, value=value, length=length, part=part), where, hint)


_TOO_LONG = f"is {{length}} characters long; the limit is {MAX_LABEL_LENGTH}."
_PART_LABEL_WORDS = {
    "invalid_type": (
        "A function label of part '{part}' is {type}, not text.",
        "Write labels as text, e.g. 'provide electricity'; put words such as yes, no, on, off or numbers in quotes.",
    ),
    "empty_label": (
        "Part '{part}' has an empty function label.",
        "Write what the part does, e.g. 'provide electricity', or remove the entry.",
    ),
    "invalid_character": (
        "The label {value!r} of part '{part}' contains control characters.",
        "Retype the label using ordinary letters, digits and punctuation.",
    ),
    "label_too_long": ("A label of part '{part}' " + _TOO_LONG, "Say it in fewer words."),
}
_GOAL_WORDS = {
    "invalid_type": (
        "'goal' is {type}, not text.",
        "Write the goal as a label, e.g. 'goal: light' (in quotes if it is a number).",
    ),
    "empty_label": ("'goal' must be a non-empty label, e.g. 'light'.", None),
    "invalid_character": (
        "'goal' contains control characters.",
        "Retype it using ordinary letters, digits and punctuation.",
    ),
    "label_too_long": ("'goal' " + _TOO_LONG, "Say it in fewer words."),
}


def _keyword_warning(label: str, part: str, keywords: list[str], where: Location) -> Diagnostic:
    """Return the warning for a label a rule cannot name: the rule reader splits it at its keywords."""
    several = len(keywords) > 1
    return warning(
        "keyword_in_label",
        f"The function '{label}' of part '{part}' contains the word{'s' if several else ''} {' and '.join(keywords)}, "
        f"which rules read as {'keywords' if several else 'a keyword'}, so no rule can use this function.",
        where,
        "Reword it without the words 'and' and 'causes' (e.g. '&' or 'makes' instead).",
    )


def _read_functions(value: object, source: SourceMap, problems: list[Diagnostic]) -> dict[str, tuple[str, ...]]:
    if not isinstance(value, Mapping):
        problems.append(
            error(
                "invalid_type",
                "'functions' must map part ids to lists of function labels.",
                source.locate("functions"),
                _FIELD_HINTS["functions"],
            )
        )
        return {}
    functions: dict[str, tuple[str, ...]] = {}
    for raw_part, raw_labels in value.items():
        part = str(raw_part)
        items: list[object]
        if isinstance(raw_labels, str):
            items = [raw_labels]
        elif isinstance(raw_labels, list):
            items = list(raw_labels)
        elif raw_labels is None:
            items = []
        else:
            problems.append(
                error(
                    "invalid_type",
                    f"The functions of part '{part}' must be a list of labels.",
                    source.locate("functions", part, part=part),
                    "e.g. '[provide electricity]'.",
                )
            )
            continue
        labels: list[str] = []
        seen: set[str] = set()
        for index, item in enumerate(items):
            problem = _label_problem(item, source.locate("functions", part, index, part=part), _PART_LABEL_WORDS, part)
            if problem is not None:
                problems.append(problem)
                continue
            assert isinstance(item, str)
            label = display_label(item)
            if normalize_label(label) in seen:
                problems.append(
                    warning(
                        "duplicate_function",
                        f"Part '{part}' has the function '{label}' twice.",
                        source.locate("functions", part, index, part=part),
                        "Once is enough.",
                    )
                )
                continue
            seen.add(normalize_label(label))
            labels.append(label)
            keywords = keywords_in(label)
            if keywords:
                problems.append(
                    _keyword_warning(label, part, keywords, source.locate("functions", part, index, part=part))
                )
        functions[part] = tuple(labels)
    return functions


def _read_object_id(data: Mapping[object, object], source: SourceMap, problems: list[Diagnostic]) -> str:
    if "object" not in data:  # reported as missing_field already
        return ""
    value = data["object"]
    if not isinstance(value, str) or not value.strip():
        problems.append(
            error(
                "invalid_type",
                "'object' must be the catalog id of an object, as text.",
                source.locate("object"),
                _FIELD_HINTS["object"],
            )
        )
        return ""
    return value.strip()


def _read_goal(data: Mapping[object, object], source: SourceMap, problems: list[Diagnostic]) -> str:
    value = data.get("goal", DEFAULT_GOAL)
    problem = _label_problem(value, source.locate("goal"), _GOAL_WORDS)
    if problem is not None:
        problems.append(problem)
        return DEFAULT_GOAL
    assert isinstance(value, str)
    return display_label(value)


def _read_rules(value: object, source: SourceMap, problems: list[Diagnostic]) -> tuple[Rule, ...]:
    if isinstance(value, str):
        value = [line for line in value.splitlines() if line.strip()]
    if not isinstance(value, list):
        problems.append(
            error(
                "invalid_type",
                "'rules' must be a list of rules, one per entry.",
                source.locate("rules"),
                _FIELD_HINTS["rules"],
            )
        )
        return ()
    rules: list[Rule] = []
    for index, raw in enumerate(value, start=1):
        where = source.locate("rules", index - 1, rule=index)
        if not isinstance(raw, str):
            problems.append(
                error(
                    "invalid_type",
                    f"Rule {index} is {type(raw).__name__}, not text.",
                    where,
                    "Write each rule as one line of text.",
                )
            )
            continue
        if len(raw) > 4 * MAX_LABEL_LENGTH:
            problems.append(
                error(
                    "label_too_long",
                    f"Rule {index} is {len(raw)} characters long.",
                    where,
                    "Split it into shorter rules with intermediate effects.",
                )
            )
            continue
        rule, rule_problems = parse_rule(raw, index, where)
        problems.extend(rule_problems)
        if rule is not None:
            rules.append(rule)
    return tuple(rules)


def read_labelling(data: object, source: SourceMap) -> tuple[Labelling | None, list[Diagnostic]]:
    """Build a step-3 mapping from parsed data; return it (None if unusable) and the problems found."""
    if not isinstance(data, Mapping):
        return None, [
            error(
                "invalid_type",
                "The mapping must be a mapping with the fields: object, functions.",
                source.locate(),
                _FIELD_HINTS["object"],
            )
        ]
    problems = _check_fields(data, MAPPING_FIELDS, MAPPING_FIELDS, source, "mapping")
    object_id = _read_object_id(data, source, problems)
    functions = _read_functions(data.get("functions", {}), source, problems)
    return Labelling(object_id, functions, source), problems


def read_model(data: object, source: SourceMap) -> tuple[CausalModel | None, list[Diagnostic]]:
    """Build a causal model from parsed data; return it (None if unusable) and the problems found.

    Only the document's shape and the rules' syntax are checked here; ``validation`` checks
    the model's meaning against the catalog.
    """
    if not isinstance(data, Mapping):
        return None, [
            error(
                "invalid_type",
                "A model must be a mapping with the fields: " + ", ".join(MODEL_FIELDS),
                source.locate(),
                _FIELD_HINTS["object"],
            )
        ]
    problems = _check_fields(data, MODEL_FIELDS, ("object", "functions", "rules"), source, "model")
    object_id = _read_object_id(data, source, problems)
    functions = _read_functions(data.get("functions", {}), source, problems)
    goal = _read_goal(data, source, problems)
    rules = _read_rules(data.get("rules", []), source, problems)
    return CausalModel(Labelling(object_id, functions, source), goal, rules), problems
