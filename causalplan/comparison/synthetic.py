"""Seeded synthetic assembly objects and causal models of any size (2 to 400 parts), for scale tests.

The object is a random tree grown from its base part: every new part has a plug that fits a
socket (same spec) on an earlier part. Some parts can also go onto a second, alternative
socket elsewhere (the two fits share the plug, so only one can be made), and some fits cover
a sibling's socket (``blocks``), so that sibling has to go in first. Every part carries one
function label.

The model uses the functions of a few *required* parts, spread over the tree (the deepest
part always among them), chained through intermediate effects to the goal ``light``, and one
effect with two alternative rules (an OR) over two more parts. The true mechanism asks for
exactly that: each required part attached (by any of its fits), and one of the two
alternatives. All other parts are decoys.

Always solvable: attaching the required parts and their ancestors in index order, each by
its primary fit, is a valid plan, because a fit only ever covers sockets of parts with a
smaller index, which that order has already filled.

``synthetic_model`` derives the model from the object's mechanism, so an object and a model
made with the same size and seed always belong together; ``synthetic_task`` gives both as a
``PlanningTask``.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from causalplan import caches
from causalplan.caches import BoundedCache
from causalplan.causal.diagnostics import Location
from causalplan.causal.model import CausalModel, Labelling
from causalplan.causal.rules import Rule, parse_rule
from causalplan.objects.model import AssemblyObject, Connector, Fit, Part, Requirement
from causalplan.pddl.task import PlanningTask, build_task

MIN_PARTS = 2
MAX_PARTS = 400
GOAL = "light"
BASE_FUNCTION = "provide power"

ALTERNATIVE_FIT_SHARE = 0.2
"""Share of parts (beyond the first few) that get a second, alternative socket elsewhere."""
BLOCKS_SHARE = 0.25
"""Share of fits onto a part with earlier children that cover one of those children's sockets."""
CHAIN_SHARE = 0.55
"""How often a new part goes onto one of the last few parts (deep chains) rather than any part."""

# (connector kind, spec, primitive): parts fit when their connectors share a spec.
_INTERFACES: tuple[tuple[str, str, str], ...] = (
    ("thread", "M3 thread", "screw"),
    ("thread", "M5 thread", "screw"),
    ("pin header", "2-pin 2.54 mm", "plug"),
    ("snap ring", "snap ring 20 mm", "clip"),
    ("peg", "peg 6 mm", "insert"),
    ("spade terminal", "spade terminal 4.8 mm", "connect"),
    ("seat", "flat seat 30 mm", "place"),
)
# fmt: off
_PART_NOUNS = (
    "housing", "bracket", "cable", "lens", "switch", "circuit board", "battery", "reflector", "spring", "cap",
    "holder", "frame", "fan", "capacitor", "resistor", "coil", "gear", "lever", "diffuser", "heat sink",
)
_FUNCTION_VERBS = (
    "conduct", "store", "switch", "guide", "focus", "regulate", "insulate", "cool", "amplify", "filter", "hold",
    "reflect", "spread", "limit", "sense", "route",
)
_FUNCTION_OBJECTS = (
    "current", "charge", "heat", "light", "voltage", "the beam", "the signal", "the cable", "the glass", "the air",
)
_EFFECTS = (
    "current flows", "the coil is energized", "the voltage is stepped down", "the circuit is closed",
    "the driver is powered", "the filament heats up", "the signal is amplified", "the beam is shaped",
    "the reflector is aligned", "the filament glows", "the lens is focused", "heat is carried away",
    "the housing is sealed", "the light is steady",
)
# fmt: on


def _part_id(index: int) -> str:
    return f"p{index:03d}"


@dataclass
class _Growing:
    """A part while the tree grows: its interface and its sockets (connector id -> spec)."""

    interface: tuple[str, str, str]
    sockets: dict[str, tuple[str, str]]
    children: list[int]


def object_id(n_parts: int, seed: int) -> str:
    """Return the id of the synthetic object of this size and seed."""
    return f"synthetic_{n_parts}_{seed}"


def synthetic_object(n_parts: int, seed: int = 0) -> AssemblyObject:
    """Return the seeded synthetic object with ``n_parts`` parts (same arguments, same object).

    Kept by size and seed (the process's ``synthetic_objects`` cache).
    """
    kept: BoundedCache[tuple[int, int], AssemblyObject] = caches.current().synthetic_objects
    return kept.get_or_make((n_parts, seed), lambda: _grown(n_parts, seed))


def _grown(n_parts: int, seed: int) -> AssemblyObject:
    if not MIN_PARTS <= n_parts <= MAX_PARTS:
        raise ValueError(f"a synthetic object has {MIN_PARTS} to {MAX_PARTS} parts, not {n_parts}")
    rng = random.Random(f"object/{n_parts}/{seed}")
    growing = [_Growing(rng.choice(_INTERFACES), {}, [])]
    parents = [-1]
    depths = [0]
    fits: list[Fit] = []
    primary: dict[int, Fit] = {}

    def add_socket(holder: int, child: int) -> str:
        connector = f"socket_{len(growing[holder].sockets) + 1}"
        kind, spec, _ = growing[child].interface
        growing[holder].sockets[connector] = (kind, spec)
        return connector

    for index in range(1, n_parts):
        if index > 3 and rng.random() < CHAIN_SHARE:
            parent = rng.randrange(max(0, index - 4), index)
        else:
            parent = rng.randrange(index)
        parents.append(parent)
        depths.append(depths[parent] + 1)
        growing.append(_Growing(rng.choice(_INTERFACES), {}, []))
        socket = add_socket(parent, index)
        blocks: tuple[tuple[str, str], ...] = ()
        earlier = growing[parent].children
        if earlier and rng.random() < BLOCKS_SHARE:
            covered = rng.choice(earlier)
            blocks = ((_part_id(parent), primary[covered].fixed_connector),)
        growing[parent].children.append(index)
        primitive = growing[index].interface[2]
        fit = Fit(
            f"f{index:03d}_{parent:03d}", primitive, _part_id(index), "plug", _part_id(parent), socket, 1.0, blocks
        )
        primary[index] = fit
        fits.append(fit)
        if index > 2 and rng.random() < ALTERNATIVE_FIT_SHARE:
            other = rng.randrange(index)
            if other != parent:
                alternative = add_socket(other, index)
                fits.append(
                    Fit(
                        f"f{index:03d}_{other:03d}",
                        primitive,
                        _part_id(index),
                        "plug",
                        _part_id(other),
                        alternative,
                        0.8,
                    )
                )

    parts = []
    for index, part in enumerate(growing):
        noun = _PART_NOUNS[index % len(_PART_NOUNS)] if index else "base"
        connectors = [Connector(cid, kind, spec) for cid, (kind, spec) in part.sockets.items()]
        if index:
            connectors.insert(0, Connector("plug", part.interface[0], part.interface[1]))
        parts.append(Part(_part_id(index), f"{noun} {index}", tuple(connectors)))

    required, alternatives = _choose_required(n_parts, depths, rng)
    fits_moving: dict[str, list[str]] = {}
    for fit in fits:
        fits_moving.setdefault(fit.moving_part, []).append(fit.id)
    mechanism = [
        Requirement(tuple(fits_moving[_part_id(index)]), f"{parts[index].name} is attached") for index in required
    ]
    if alternatives is not None:
        first, second = alternatives
        mechanism.append(
            Requirement(
                tuple(fits_moving[_part_id(first)] + fits_moving[_part_id(second)]),
                f"{parts[first].name} or {parts[second].name} is attached",
            )
        )
    return AssemblyObject(
        id=object_id(n_parts, seed),
        name=f"synthetic lamp ({n_parts} parts, seed {seed})",
        category="electric",
        goal=GOAL,
        description=f"A random tree of {n_parts} parts grown from its base (seed {seed}).",
        base=_part_id(0),
        parts=tuple(parts),
        fits=tuple(fits),
        mechanism=tuple(mechanism),
        mechanism_explanation="Light needs every required part attached, and one of two alternative parts.",
    )


def _choose_required(n_parts: int, depths: list[int], rng: random.Random) -> tuple[list[int], tuple[int, int] | None]:
    """Return the required parts (deepest first, spread over depths) and the OR's two parts."""
    others = list(range(1, n_parts))
    count = max(1, min(n_parts - 1, 2 + round(math.log2(n_parts))))
    if n_parts - 1 >= count + 2:
        count = min(count, n_parts - 3)  # leave two parts for the alternatives
    deepest = max(others, key=lambda index: (depths[index], -index))
    by_depth = sorted((index for index in others if index != deepest), key=lambda index: (depths[index], index))
    required = [deepest]
    rest = count - 1
    if rest > 0:  # one part from each of ``rest`` depth bands, so shallow and deep ones mix
        band = len(by_depth) / rest
        required += [
            by_depth[rng.randrange(int(i * band), max(int(i * band) + 1, int((i + 1) * band)))] for i in range(rest)
        ]
    required = sorted(set(required), key=lambda index: (-depths[index], index))
    free = [index for index in others if index not in required]
    pool = free if len(free) >= 2 else others
    if len(pool) < 2:
        return required, None
    first, second = sorted(rng.sample(pool, 2))
    return required, (first, second)


def _function_labels(n_parts: int, rng: random.Random) -> list[str]:
    phrases = [f"{verb} {thing}" for verb in _FUNCTION_VERBS for thing in _FUNCTION_OBJECTS]
    rng.shuffle(phrases)
    return [BASE_FUNCTION] + [f"{phrases[(index - 1) % len(phrases)]} {index}" for index in range(1, n_parts)]


def _effect_labels(count: int) -> list[str]:
    return [_EFFECTS[i] if i < len(_EFFECTS) else f"{_EFFECTS[i % len(_EFFECTS)]} {i}" for i in range(count)]


def synthetic_model(obj: AssemblyObject, seed: int = 0) -> CausalModel:
    """Return the causal model of a synthetic object, derived from its true mechanism.

    Every part carries one function; the required parts' functions (with the base's
    ``provide power``) are chained in groups of one to three through intermediate effects,
    the two alternatives each cause one more effect (an OR), and both lead to ``light``.
    """
    rng = random.Random(f"model/{obj.id}/{seed}")
    index_of = {part_id: index for index, part_id in enumerate(obj.part_ids)}
    labels = _function_labels(len(obj.parts), rng)
    moving = {fit.id: fit.moving_part for fit in obj.fits}
    required: list[str] = []
    alternatives: list[str] = []
    for requirement in obj.mechanism:
        parts = sorted({moving[fit_id] for fit_id in requirement.any_of}, key=index_of.__getitem__)
        if len(parts) == 1:
            required.append(parts[0])
        else:
            alternatives = parts
    groups: list[list[str]] = []
    remaining = list(required)
    rng.shuffle(remaining)
    while remaining:
        size = rng.randint(1, 3)
        groups.append(remaining[:size])
        remaining = remaining[size:]
    effects = _effect_labels(len(groups) + 1)
    texts: list[str] = []
    previous = BASE_FUNCTION
    for number, group in enumerate(groups):
        causes = [previous, *(labels[index_of[part]] for part in group)]
        texts.append(f"{' AND '.join(causes)} CAUSES {effects[number]}")
        previous = effects[number]
    either = effects[-1]
    if len(alternatives) >= 2:
        texts += [f"{labels[index_of[part]]} CAUSES {either}" for part in alternatives]
    else:  # too few parts for two alternatives: the OR is a second, stronger way to the same effect
        texts += [f"{previous} CAUSES {either}", f"{previous} AND {BASE_FUNCTION} CAUSES {either}"]
    texts.append(f"{previous} AND {either} CAUSES {GOAL}")
    rules: list[Rule] = []
    for number, text in enumerate(texts, start=1):
        rule, problems = parse_rule(text, number, Location(rule=number))
        if rule is None:  # pragma: no cover - the texts above are always well-formed
            raise AssertionError(f"synthetic rule {text!r} does not parse: {problems}")
        rules.append(rule)
    functions = {part_id: (labels[index],) for index, part_id in enumerate(obj.part_ids)}
    return CausalModel(Labelling(obj.id, functions), GOAL, tuple(rules))


def object_document(obj: AssemblyObject) -> dict[str, object]:
    """Return ``obj`` as the catalog's object file holds it (``objects/schema.py``)."""
    return {
        "id": obj.id,
        "name": obj.name,
        "category": obj.category,
        "goal": obj.goal,
        "description": obj.description,
        "base": obj.base,
        "parts": [
            {
                "id": part.id,
                "name": part.name,
                "connectors": [{"id": c.id, "kind": c.kind, "spec": c.spec} for c in part.connectors],
            }
            for part in obj.parts
        ],
        "fits": [
            {
                "id": fit.id,
                "primitive": fit.primitive,
                "moving": f"{fit.moving_part}.{fit.moving_connector}",
                "fixed": f"{fit.fixed_part}.{fit.fixed_connector}",
                "probability": fit.probability,
                "blocks": [f"{part}.{connector}" for part, connector in fit.blocks],
                **({"text": fit.text} if fit.text is not None else {}),
            }
            for fit in obj.fits
        ],
        "mechanism": {
            "explanation": obj.mechanism_explanation,
            "requires": [{"any": list(req.any_of), "says": req.says} for req in obj.mechanism],
        },
    }


def synthetic_task(n_parts: int, seed: int = 0) -> PlanningTask:
    """Return the planning task of the synthetic object and model of this size and seed."""
    obj = synthetic_object(n_parts, seed)
    return build_task(synthetic_model(obj, seed), obj)
