"""Synthetic participants: models and step-3 mappings with the paper's error kinds, at rates you set.

Each training object has one correct way to say how it makes light, as concepts (what a part
does) and rules between them; a participant words each concept in one of several ways, and
each error kind happens to a participant with its own probability:

- ``non_causal``: a function that does not cause the goal ("hold things together") is made a
  necessary cause of it;
- ``effect_as_cause``: an effect of the light ("diffuse light") is made a necessary cause;
- ``uncaused_intermediate``: the rule producing the intermediate effect is left out, so the
  effect is used but nothing causes it;
- ``object_specific``: the functions are worded for this object ("provide electricity"); such
  words do not fit an object of another category, which then gets no part for them in step 3;
- ``paraphrase``: a label is worded in another way that means the same;
- ``missed_part``: in step 3 one part that should carry functions is given none.

The same seed gives the same participants.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from causalplan.errors import CausalPlanError
from causalplan.objects.catalog import Catalog
from causalplan.studies.far_generalization import PaperCondition, span_of

ERROR_KINDS = ("non_causal", "effect_as_cause", "uncaused_intermediate", "object_specific", "paraphrase", "missed_part")
DEFAULT_RATES = {
    "non_causal": 0.1,
    "effect_as_cause": 0.2,
    "uncaused_intermediate": 0.1,
    "object_specific": 0.4,
    "paraphrase": 0.5,
    "missed_part": 0.1,
}
"""The rates ``population`` and ``crowd-curve`` use unless told otherwise (a plausible crowd, not measured)."""


class UnknownScenarioError(CausalPlanError):
    """There is no synthetic scenario for this training or test object."""

    code = "unknown_scenario"


@dataclass(frozen=True)
class Concept:
    """What one part does: general words (fit any light source) and this object's own words."""

    part: str
    general: tuple[str, ...]
    specific: tuple[str, ...] = ()


@dataclass(frozen=True)
class Scenario:
    """A training object's correct model as concepts and rules, and where each concept sits on test objects."""

    object_id: str
    concepts: dict[str, Concept]
    rules: tuple[tuple[tuple[str, ...], str], ...]
    """(causes, effect) by concept name; the effect of the last rule is the goal."""
    effects: dict[str, Concept]
    """Intermediate effects (their part is unused)."""
    decorative_part: str
    shade_part: str
    test_parts: dict[str, dict[str, tuple[str, ...]]] = field(default_factory=dict)
    """Test object -> concept (and 'hold', 'diffuse') -> the parts that carry it there."""


HOLD = ("hold things together", "keep parts in place", "keep the parts in place")
DIFFUSE = ("diffuse light", "spread the light", "soften the light")

SCENARIOS = {
    "desk_lamp": Scenario(
        "desk_lamp",
        {
            "power": Concept(
                "base_with_cables",
                ("provide energy", "supply energy", "energy source"),
                ("provide electricity", "supply power", "gives electricity"),
            ),
            "start": Concept(
                "light_bulb",
                ("start the process", "set it going", "start it"),
                ("close the circuit", "complete the circuit", "connect the circuit"),
            ),
            "convert": Concept(
                "light_bulb",
                ("turn energy into light", "convert energy to light", "make light from energy"),
                ("turn electricity into light", "convert electricity to light", "make light from electricity"),
            ),
        },
        ((("power", "start"), "release"), (("release", "convert"), "light")),
        {
            "release": Concept(
                "", ("energy is released", "energy flows", "energy comes out"), ("electricity flows", "current runs")
            )
        },
        "base_with_cables",
        "shade",
        {
            "flashlight": {
                "power": ("batteries",),
                "start": ("head",),
                "convert": ("head",),
                "hold": ("case",),
                "diffuse": ("head",),
            },
            "candle": {"power": ("wax",), "start": ("match",), "convert": ("wick",)},
            "kerosene_lamp": {
                "power": ("fuel_tank",),
                "start": ("lighter",),
                "convert": ("wick",),
                "hold": ("glass_chimney",),
                "diffuse": ("glass_chimney",),
            },
        },
    ),
    "candle": Scenario(
        "candle",
        {
            "fuel": Concept(
                "wax",
                ("provide energy", "energy source", "store energy"),
                ("provide fuel", "fuel source", "hold the fuel"),
            ),
            "draw": Concept(
                "wick",
                ("carry the energy", "bring the energy up", "move the energy"),
                ("draw up the fuel", "soak up fuel", "carry the fuel"),
            ),
            "start": Concept(
                "match", ("start the process", "set it going", "start it"), ("start a flame", "ignite", "make fire")
            ),
        },
        ((("fuel", "draw"), "release"), (("release", "start"), "light")),
        {
            "release": Concept(
                "", ("energy is released", "energy at the tip", "energy comes out"), ("fuel at the tip", "wet wick")
            )
        },
        "wax",
        "wick",
        {
            "kerosene_lamp": {
                "fuel": ("fuel_tank",),
                "draw": ("wick",),
                "start": ("lighter",),
                "hold": ("burner",),
                "diffuse": ("glass_chimney",),
            },
            "flashlight": {
                "fuel": ("batteries",),
                "draw": ("head",),
                "start": ("head",),
                "hold": ("case",),
                "diffuse": ("head",),
            },
            "desk_lamp": {
                "fuel": ("base_with_cables",),
                "draw": ("light_bulb",),
                "start": ("light_bulb",),
                "hold": ("base_with_cables",),
                "diffuse": ("shade",),
            },
        },
    ),
}
CATEGORY = {"desk_lamp": "electric", "flashlight": "electric", "candle": "combustion", "kerosene_lamp": "combustion"}


def scenario_for(training: str) -> Scenario:
    """Return the synthetic scenario of a training object; UnknownScenarioError names the known ones."""
    if training not in SCENARIOS:
        raise UnknownScenarioError(
            f"There is no synthetic scenario for '{training}'; there is one for: {', '.join(sorted(SCENARIOS))}."
        )
    return SCENARIOS[training]


def _words(rng: random.Random, concept: Concept, specific: bool, paraphrase: float) -> str:
    choices = concept.specific if specific and concept.specific else concept.general
    return rng.choice(choices[1:]) if rng.random() < paraphrase else choices[0]


def participant(
    rng: random.Random, scenario: Scenario, tests: tuple[str, ...], rates: dict[str, float], person: str
) -> list[dict[str, object]]:
    """Return one participant's trial lines (one per test object), with the errors they made."""
    made = [kind for kind in ERROR_KINDS if kind != "paraphrase" and rng.random() < rates.get(kind, 0.0)]
    specific = "object_specific" in made
    words = {name: _words(rng, concept, specific, rates["paraphrase"]) for name, concept in scenario.concepts.items()}
    words |= {name: _words(rng, concept, specific, rates["paraphrase"]) for name, concept in scenario.effects.items()}
    words["light"] = "light"
    extra: list[str] = []
    functions: dict[str, list[str]] = {}
    for name, concept in scenario.concepts.items():
        functions.setdefault(concept.part, []).append(words[name])
    if "non_causal" in made:
        words["hold"] = rng.choice(HOLD) if rng.random() < rates["paraphrase"] else HOLD[0]
        functions.setdefault(scenario.decorative_part, []).append(words["hold"])
        extra.append("hold")
    if "effect_as_cause" in made:
        words["diffuse"] = rng.choice(DIFFUSE) if rng.random() < rates["paraphrase"] else DIFFUSE[0]
        functions.setdefault(scenario.shade_part, []).append(words["diffuse"])
        extra.append("diffuse")
    rules = []
    for number, (causes, effect) in enumerate(scenario.rules):
        is_goal_rule = number == len(scenario.rules) - 1
        if "uncaused_intermediate" in made and not is_goal_rule:
            continue
        names = list(causes) + (extra if is_goal_rule else [])
        rules.append(" AND ".join(words[name] for name in names) + f" CAUSES {words[effect]}")
    model = {"object": scenario.object_id, "goal": "light", "functions": functions, "rules": rules}
    lines: list[dict[str, object]] = []
    for test in tests:
        where = scenario.test_parts[test]
        mapped: dict[str, list[str]] = {}
        far = CATEGORY.get(test) != CATEGORY.get(scenario.object_id)
        for name in [*scenario.concepts, *extra]:
            if far and specific and name in scenario.concepts and scenario.concepts[name].specific:
                continue  # "provide electricity" does not fit a candle's wax: nothing gets it
            for part in where.get(name, ()):
                mapped.setdefault(part, []).append(words[name])
        if "missed_part" in made and mapped:
            del mapped[rng.choice(sorted(mapped))]
        lines.append({"id": person, "model": model, "mapping": {"object": test, "functions": mapped}, "errors": made})
    return lines


def population(
    training: str, count: int, seed: int, rates: dict[str, float] | None = None, tests: tuple[str, ...] = ()
) -> list[dict[str, object]]:
    """Return ``count`` synthetic participants' trial lines (ids p0001...), reproducible from ``seed``."""
    scenario = scenario_for(training)
    chosen = tests or tuple(scenario.test_parts)
    unknown = [test for test in chosen if test not in scenario.test_parts]
    if unknown:
        raise UnknownScenarioError(
            f"The {training} scenario has no mapping for {', '.join(unknown)}; "
            f"it has one for: {', '.join(scenario.test_parts)}."
        )
    settings = DEFAULT_RATES | (rates or {})
    rng = random.Random(seed)
    lines: list[dict[str, object]] = []
    for number in range(1, count + 1):
        lines.extend(participant(rng, scenario, chosen, settings, f"p{number:04d}"))
    return lines


# --- the paper's far-generalization design: two training objects, novel test objects -------------

ROLES = ("supply", "flow", "start", "light")
"""What the parts of a light source do, in the few roles every catalog object's mechanism has."""
ROLE_PARTS: dict[str, dict[str, tuple[str, ...]]] = {
    "desk_lamp": {
        "supply": ("base_with_cables",),
        "flow": ("base_with_cables",),
        "start": ("base_with_cables",),
        "light": ("light_bulb",),
    },
    "flashlight": {"supply": ("batteries",), "flow": ("head",), "start": ("head",), "light": ("head",)},
    "headlamp": {"supply": ("batteries",), "flow": ("switch",), "start": ("switch",), "light": ("led",)},
    "solar_lantern": {
        "supply": ("solar_panel", "crank_handle"),
        "flow": ("battery",),
        "start": ("body",),
        "light": ("led_lamp",),
    },
    "candle": {"supply": ("wax",), "flow": ("wick",), "start": ("match",), "light": ("wick",)},
    "kerosene_lamp": {"supply": ("fuel_tank",), "flow": ("burner",), "start": ("lighter",), "light": ("wick",)},
    "oil_lamp": {"supply": ("oil_bottle",), "flow": ("wick",), "start": ("match",), "light": ("wick",)},
    "gas_lantern": {"supply": ("burner",), "flow": ("valve_knob",), "start": ("igniter",), "light": ("mantle",)},
}
"""Object -> role -> the parts that play it (several: any one will do, as in the object's mechanism)."""
WORDS = {
    "general": ("supply energy", "let the energy flow", "start the process", "turn energy into light"),
    "electric": ("provide electricity", "close the circuit", "switch it on", "turn electricity into light"),
    "combustion": ("provide fuel", "draw up the fuel", "light the fuel", "burn with a flame"),
}
"""The words for the roles: general ones fit every light source, a category's own fit only that category."""
RELEASED = {"general": "energy is released", "electric": "electricity flows", "combustion": "the fuel burns"}


def _paper_model(training: tuple[str, ...], vocabularies: list[str], category: dict[str, str]) -> dict[str, object]:
    """Return a participant's one model of two training objects, each labelled in its vocabulary."""
    functions: dict[str, list[str]] = {}
    for object_id in training:
        words = dict(zip(ROLES, WORDS[vocabularies[0] if len(vocabularies) == 1 else category[object_id]], strict=True))
        for role, parts in ROLE_PARTS[object_id].items():
            for part in parts:
                functions.setdefault(f"{object_id}.{part}", []).append(words[role])
    rules = []
    for vocabulary in vocabularies:
        supply, flow, start, light = WORDS[vocabulary]
        rules.append(f"{supply} AND {flow} AND {start} CAUSES {RELEASED[vocabulary]}")
        rules.append(f"{RELEASED[vocabulary]} AND {light} CAUSES light")
    return {"object": "_and_".join(training), "goal": "light", "functions": functions, "rules": rules}


def _paper_mapping(
    test: str, vocabularies: list[str], category: str, slip: bool, rng: random.Random
) -> dict[str, object]:
    """Return a participant's step-3 mapping of a test object: their words on the parts they fit.

    Words of another category do not fit: only the part that makes the light gets a label.
    """
    fitting = [v for v in vocabularies if v in ("general", category)]
    mapped: dict[str, list[str]] = {}
    for vocabulary in fitting or vocabularies[:1]:
        for role, word in zip(ROLES, WORDS[vocabulary], strict=True):
            if fitting or role == "light":
                for part in ROLE_PARTS[test][role]:
                    mapped.setdefault(part, []).append(word)
    if slip and len(mapped) > 1:
        del mapped[rng.choice(sorted(mapped))]
    return {"object": test, "functions": mapped}


def paper_population(
    conditions: Sequence[PaperCondition],
    catalog: Catalog,
    per_condition: int,
    seed: int,
    knobs: Mapping[str, Mapping[str, float]],
) -> list[dict[str, object]]:
    """Return synthetic participants of the paper's design, one line per test object, reproducible from ``seed``.

    ``knobs[span]`` (span: 'one category' or 'both categories') sets, for participants trained on
    one category or on both, the chance of wording the model in general terms (``abstract``;
    otherwise in the training categories' own words, which fit no object of another category)
    and of leaving a part out in step 3 (``slip``). Each line carries the participant's
    condition, training objects, the test object and its position, and the model and mapping.
    """
    named = sorted({o for c in conditions for o in (*c.training, *c.tests)})
    unknown = [object_id for object_id in named if object_id not in ROLE_PARTS]
    if unknown:
        raise UnknownScenarioError(
            f"There is no synthetic scenario for {', '.join(unknown)}; there is one for: {', '.join(ROLE_PARTS)}."
        )
    category = {object_id: catalog.get(object_id).category for object_id in named}
    rng = random.Random(seed)
    lines: list[dict[str, object]] = []
    for condition in conditions:
        trained = list(dict.fromkeys(category[o] for o in condition.training))
        settings = knobs[span_of(trained)]
        for number in range(per_condition):
            person = f"{condition.name}-{number:03d}".replace(" ", "_")
            abstract = rng.random() < settings["abstract"]
            vocabularies = ["general"] if abstract else trained
            model = _paper_model(condition.training, vocabularies, category)
            order = condition.tests if number % 2 == 0 else condition.tests[::-1]  # both test orders, alternating
            for position, test in enumerate(order, start=1):
                slip = rng.random() < settings["slip"]
                lines.append(
                    {
                        "id": f"{person}-{test}",
                        "participant_id": person,
                        "condition": condition.name,
                        "training": list(condition.training),
                        "test": test,
                        "position": position,
                        "abstract": abstract,
                        "model": model,
                        "mapping": _paper_mapping(test, vocabularies, category[test], slip, rng),
                        "errors": ["missed_part"] if slip else [],
                    }
                )
    return lines
