"""An experiment's design: conditions with their training and test objects, and its options.

``read_design`` checks a definition against the catalog and reports every problem at once
(``InvalidExperimentError`` with ``details['errors']``), in words a researcher can act on.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from causalplan.causal.labels import closest, display_label, has_control_characters, normalize_label
from causalplan.errors import UnknownObjectError
from causalplan.objects.catalog import Catalog
from causalplan.studies.errors import InvalidExperimentError
from causalplan.transfer.generalization import near_or_far

MAX_TRAINING_OBJECTS = 2
"""One model explains one training object, or two (the paper's far-generalization experiment)."""


@dataclass(frozen=True)
class Condition:
    """One condition: the objects a model is built from, and those it is then tried on."""

    name: str
    training: tuple[str, ...]
    tests: tuple[str, ...]

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "training": list(self.training), "tests": list(self.tests)}


@dataclass(frozen=True)
class Design:
    """What an experiment asks of its participants."""

    conditions: tuple[Condition, ...]
    counterbalance_training: bool = True
    counterbalance_tests: bool = True
    show_verdict: bool = True
    tutorial: bool = True
    robot_verdict: bool = False
    """Whether a transfer also needs the robot to carry out the plan (``robot_cannot_execute`` when not)."""

    def condition(self, name: str) -> Condition:
        """Return the condition called ``name`` (KeyError when there is none)."""
        for condition in self.conditions:
            if condition.name == name:
                return condition
        raise KeyError(name)

    def as_dict(self) -> dict[str, Any]:
        return {**asdict(self), "conditions": [condition.as_dict() for condition in self.conditions]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Design:
        """Return the design stored by ``as_dict`` (already checked when it was stored)."""
        return cls(
            tuple(
                Condition(str(item["name"]), tuple(item["training"]), tuple(item["tests"]))
                for item in data["conditions"]
            ),
            bool(data.get("counterbalance_training", True)),
            bool(data.get("counterbalance_tests", True)),
            bool(data.get("show_verdict", True)),
            bool(data.get("tutorial", True)),
            bool(data.get("robot_verdict", False)),  # designs stored before the option was added: off
        )


def _object_problems(ids: Sequence[str], catalog: Catalog, where: str) -> list[str]:
    problems = []
    for object_id in ids:
        if object_id not in catalog.objects:
            guess = closest(object_id, sorted(catalog.objects))
            hint = f" Did you mean '{guess}'?" if guess else f" Known objects: {', '.join(sorted(catalog.objects))}."
            problems.append(f"{where}: there is no object '{object_id}' in the catalog.{hint}")
    return problems


def _condition_problems(condition: Condition, catalog: Catalog) -> list[str]:
    where = f"Condition '{condition.name}'"
    problems = _object_problems([*condition.training, *condition.tests], catalog, where)
    if not condition.training:
        problems.append(f"{where} has no training object.")
    if len(condition.training) > MAX_TRAINING_OBJECTS:
        problems.append(f"{where} has {len(condition.training)} training objects; a model explains one or two.")
    if not condition.tests:
        problems.append(f"{where} has no test object.")
    for ids, what in ((condition.training, "training"), (condition.tests, "test")):
        repeated = sorted({item for item in ids if ids.count(item) > 1})
        if repeated:
            problems.append(f"{where} lists the {what} object(s) {', '.join(repeated)} more than once.")
    both = sorted(set(condition.training) & set(condition.tests))
    if both:
        problems.append(f"{where}: {', '.join(both)} cannot be both a training and a test object (tests are new).")
    if problems:
        return problems
    goals = {object_id: catalog.get(object_id).goal for object_id in [*condition.training, *condition.tests]}
    if len({normalize_label(goal) for goal in goals.values()}) > 1:
        listed = ", ".join(f"{object_id} ({goal})" for object_id, goal in goals.items())
        problems.append(f"{where} mixes objects with different goals: {listed}. One model explains one goal.")
    return problems


def _name_problem(name: str, what: str) -> str | None:
    if not name.strip():
        return f"The {what} is empty."
    if has_control_characters(name):
        return f"The {what} {name!r} contains control characters."
    return None


def read_design(
    name: str,
    conditions: Sequence[Mapping[str, Any]],
    options: Mapping[str, bool],
    catalog: Catalog,
) -> tuple[str, Design]:
    """Return the experiment's tidied name and its design; InvalidExperimentError lists every problem."""
    problems: list[str] = []
    problem = _name_problem(name, "experiment's name")
    if problem:
        problems.append(problem)
    read: list[Condition] = []
    seen: dict[str, str] = {}
    for number, item in enumerate(conditions, start=1):
        condition_name = display_label(str(item.get("name", "")))
        problem = _name_problem(condition_name, f"name of condition {number}")
        if problem:
            problems.append(problem)
            continue
        key = normalize_label(condition_name)
        if key in seen:
            problems.append(f"Two conditions are called '{condition_name}'; give each its own name.")
            continue
        seen[key] = condition_name
        condition = Condition(
            condition_name,
            tuple(str(item_id).strip() for item_id in item.get("training", [])),
            tuple(str(item_id).strip() for item_id in item.get("tests", [])),
        )
        problems += _condition_problems(condition, catalog)
        read.append(condition)
    if not conditions:
        problems.append("The experiment has no condition; add at least one (e.g. 'near').")
    if problems:
        raise InvalidExperimentError(
            "The experiment cannot be created: "
            + " ".join(problems[:3])
            + (" (and more)" if len(problems) > 3 else ""),
            details={"errors": problems},
        )
    design = Design(
        tuple(read),
        counterbalance_training=options.get("counterbalance_training", True),
        counterbalance_tests=options.get("counterbalance_tests", True),
        show_verdict=options.get("show_verdict", True),
        tutorial=options.get("tutorial", True),
        robot_verdict=options.get("robot_verdict", False),
    )
    return display_label(name), design


def generalization(training: Sequence[str], test: str, catalog: Catalog) -> str:
    """Return ``near`` when the test object shares a category with a training object, else ``far``."""
    return near_or_far((catalog.get(object_id).category for object_id in training), catalog.get(test).category)


def generalization_of(training: Sequence[str], test: str, catalog: Catalog) -> str | None:
    """Return ``near`` or ``far`` for a test object after these training objects (None: the catalog lost one)."""
    try:
        return generalization(training, test, catalog)
    except UnknownObjectError:  # the catalog no longer has an object the experiment used
        return None
