"""The paper's far-generalization experiment as a template: near and far conditions over the catalog.

Each participant models two training objects with one causal model: in a near condition both
come from one category, in the far condition one comes from each. Every condition is then
tested on the same two novel objects, one of each category. The template counterbalances
which category the near conditions train on (one near condition per category) and which
objects are shown (``sets`` rotations of each category's objects: set k trains on the next two
objects of the rotation and tests on the one after them, so no object is trained on and tested
in one set); the order of the training and the test objects is counterbalanced per participant
by the experiment's balanced Latin squares (its ``counterbalance_*`` options, on here).

Whether a test is near or far is a property of the test object and the training objects the
participant saw (``design.generalization``), not of the condition's name: in the far condition both tests
share a category with a training object.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from causalplan.errors import CausalPlanError
from causalplan.objects.catalog import Catalog
from causalplan.studies.design import generalization
from causalplan.studies.statistics import Comparison, Proportion, fisher, wilson
from causalplan.studies.trials import TrialRow

TEMPLATE = "far_generalization"
"""The template's name in ``POST /v1/experiments`` (``"template": "far_generalization"``)."""
TEMPLATE_TITLE = "the paper's far-generalization experiment"
CATEGORIES = ("electric", "combustion")
GOAL = "light"
PER_CONDITION = 2
"""Training objects per condition, and test objects per condition (one per category)."""
SET_NAMES = "ABCDEFGH"
ONE_CATEGORY, BOTH_CATEGORIES = "one category", "both categories"
SPANS = (ONE_CATEGORY, BOTH_CATEGORIES)
"""Whether a participant's training objects come from one category or from both."""


class DesignError(CausalPlanError):
    """The paper's design cannot be made or a condition breaks it; ``details['errors']`` lists why."""

    code = "invalid_design"


@dataclass(frozen=True)
class PaperCondition:
    """One condition of the paper's design: two training objects, two novel test objects."""

    name: str
    training: tuple[str, ...]
    tests: tuple[str, ...]

    def as_dict(self) -> dict[str, object]:
        """Return the condition as ``POST /v1/experiments`` takes it."""
        return {"name": self.name, "training": list(self.training), "tests": list(self.tests)}


def object_pools(catalog: Catalog, categories: Sequence[str] = CATEGORIES) -> dict[str, list[str]]:
    """Return each category's objects that make light, by id; DesignError when one has fewer than three."""
    pools = {
        category: sorted(o.id for o in catalog.objects.values() if o.category == category and o.goal == GOAL)
        for category in categories
    }
    problems = [
        f"The paper's design needs at least {PER_CONDITION + 1} {category} objects that make {GOAL} "
        f"({PER_CONDITION} to train on and a novel one to test on); the catalog has {len(ids)}"
        + (f": {', '.join(ids)}." if ids else ".")
        for category, ids in pools.items()
        if len(ids) < PER_CONDITION + 1
    ]
    if problems:
        raise DesignError(" ".join(problems), details={"errors": problems})
    return pools


def _rotation(pool: Sequence[str], shift: int) -> tuple[tuple[str, ...], str]:
    """Return the training pair and the novel test object of one rotation of a category's objects."""
    turned = [pool[(shift + index) % len(pool)] for index in range(PER_CONDITION + 1)]
    return tuple(turned[:PER_CONDITION]), turned[PER_CONDITION]


def far_generalization_conditions(
    catalog: Catalog, sets: int = 2, categories: Sequence[str] = CATEGORIES
) -> list[PaperCondition]:
    """Return the paper's conditions: per set, one near condition per category and one far condition.

    Set k rotates each category's objects by k/sets of the way round, so the sets train on
    different objects and test on different novel ones.
    """
    if len(categories) != PER_CONDITION:
        raise DesignError(f"The paper's design compares two categories, not {len(categories)}.")
    pools = object_pools(catalog, categories)
    most = min(*(len(pool) for pool in pools.values()), len(SET_NAMES))
    if not 1 <= sets <= most:
        raise DesignError(
            f"The design can rotate the objects into 1 to {most} sets with this catalog, not {sets}.",
            details={"errors": [f"sets must be between 1 and {most}"]},
        )
    conditions = []
    for number in range(sets):
        chosen = {category: _rotation(pool, number * len(pool) // sets) for category, pool in pools.items()}
        tests = tuple(test for _, test in chosen.values())
        suffix = f" {SET_NAMES[number]}" if sets > 1 else ""
        for category, (training, _) in chosen.items():
            conditions.append(PaperCondition(f"near {category}{suffix}", training, tests))
        # The far condition takes one training object of each category, alternating which one.
        far = tuple(training[(number + index) % PER_CONDITION] for index, (training, _) in enumerate(chosen.values()))
        conditions.append(PaperCondition(f"far{suffix}", far, tests))
    check_conditions(conditions, catalog, categories)
    return conditions


def check_conditions(
    conditions: Sequence[PaperCondition], catalog: Catalog, categories: Sequence[str] = CATEGORIES
) -> None:
    """Refuse conditions that break the paper's design; DesignError lists every problem and why."""
    problems = []
    for condition in conditions:
        where = f"Condition '{condition.name}'"
        trained_on = sorted(set(condition.tests) & set(condition.training))
        for test in trained_on:
            problems.append(
                f"{where} trains on {test} and tests on it too: the paper's test objects are novel, since it "
                "asks whether a model explains an object the participant did not model; pick another "
                f"{catalog.get(test).category} object to test on."
            )
        if len(condition.training) != PER_CONDITION:
            problems.append(f"{where} has {len(condition.training)} training object(s); the paper's design has two.")
        test_categories = sorted(catalog.get(test).category for test in condition.tests)
        if test_categories != sorted(categories):
            problems.append(
                f"{where} tests on {', '.join(condition.tests) or 'nothing'}; the paper's design tests on one "
                f"novel object of each category ({', '.join(categories)})."
            )
    if problems:
        raise DesignError(
            "The paper's design cannot be made: "
            + " ".join(problems[:2])
            + (" (and more)" if len(problems) > 2 else ""),
            details={"errors": problems},
        )


def template_conditions(
    name: str, catalog: Catalog, given: Sequence[Mapping[str, object]] = ()
) -> list[dict[str, object]]:
    """Return the conditions of the template ``name`` as ``POST /v1/experiments`` takes them.

    Without ``given`` conditions the template makes them from the catalog; with them, it checks
    that they follow the paper's design (DesignError says which do not, and why).
    """
    if name != TEMPLATE:
        raise DesignError(f"There is no design template '{name}'; there is '{TEMPLATE}'.")
    if not given:
        return [condition.as_dict() for condition in far_generalization_conditions(catalog)]
    conditions = [
        PaperCondition(str(item.get("name", "")), _ids(item.get("training")), _ids(item.get("tests"))) for item in given
    ]
    known = [c for c in conditions if all(o in catalog.objects for o in (*c.training, *c.tests))]
    check_conditions(known, catalog)  # unknown objects: the experiment's own check names them
    return [dict(item) for item in given]


def _ids(value: object) -> tuple[str, ...]:
    return tuple(str(item) for item in value) if isinstance(value, list | tuple) else ()


def describe(conditions: Sequence[PaperCondition], catalog: Catalog) -> Mapping[str, Mapping[str, str]]:
    """Return, per condition, each test object's relation (near or far) to that condition's training objects."""
    return {c.name: {test: generalization(c.training, test, catalog) for test in c.tests} for c in conditions}


def span_of(training_categories: Iterable[str]) -> str:
    """Return ``one category`` when the training objects' categories are one, else ``both categories``."""
    return ONE_CATEGORY if len(set(training_categories)) <= 1 else BOTH_CATEGORIES


def training_span(row: TrialRow, catalog: Catalog) -> str:
    """Return whether this participant's training objects come from one category or from both."""
    return span_of(catalog.get(object_id).category for object_id in row.training_objects)


def relation_shares(rows: Sequence[TrialRow], catalog: Catalog) -> dict[tuple[str, str], Proportion]:
    """Return the transfer rate (Wilson interval) of each training span x the test's relation (near, far)."""
    outcomes: dict[tuple[str, str], list[int]] = {}
    for row in rows:
        if row.outcome is not None:
            outcomes.setdefault((training_span(row, catalog), row.generalization), []).append(row.outcome)
    kinds = [(span, kind) for span in SPANS for kind in ("near", "far") if (span, kind) in outcomes]
    return {key: wilson(sum(outcomes[key]), len(outcomes[key])) for key in kinds}


def prediction_tests(rows: Sequence[TrialRow], catalog: Catalog) -> list[Comparison]:
    """Return Fisher's tests of the paper's two predictions, pooled over conditions (before Holm).

    Each test counts as near or far by its relation to the participant's own training objects.
    1. Trained on one category, models transfer more to near test objects than to far ones.
    2. Trained on both categories, models transfer (to both categories) more than models trained
       on one category transfer to the other category.
    """
    shares = relation_shares(rows, catalog)
    found = []
    one_near, one_far = shares.get((ONE_CATEGORY, "near")), shares.get((ONE_CATEGORY, "far"))
    if one_near and one_far:
        found.append(
            fisher(
                "trained on one category: near vs far test objects",
                ("near test objects", one_near),
                ("far test objects", one_far),
                "greater",
            )
        )
    both = shares.get((BOTH_CATEGORIES, "near"))
    if both and one_far:
        found.append(
            fisher(
                "trained on both categories vs on one category, test objects of an untrained category for the latter",
                ("trained on both categories", both),
                ("trained on one category, far tests", one_far),
                "greater",
            )
        )
    return found
