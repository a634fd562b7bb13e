"""Seeded families of large MDP tasks whose optimum is known in closed form, for tests and benchmarks.

The MDP planner proves its answers with its own bounds; these families check it against
figures worked out by hand, at sizes (80 relevant parts and more) that no enumeration reaches:

* ``independent_components``: ``count`` components of five parts on the base, each on its
  own base socket. In a component a holder ``h`` goes onto the base; ``x`` has two plugs, one
  for each of two sockets of ``h`` (an alternative: a failed try leaves the other plug); ``y``
  and ``u`` share a socket of ``h`` and the model needs one of them (an OR), ``u`` also fits a
  socket of its own; ``v`` has one fit. A failure makes both connectors of that fit unusable,
  so the best a component can do is ``p_h (1 - (1 - x1)(1 - x2)) (1 - (1 - y)(1 - u2)) p_v``
  (``y`` into the shared socket and then ``u`` into its own, or the other way round; ``u`` into
  the shared socket first leaves ``y`` nothing and is drawn less reliable), and the best
  success probability of the object is the product over the components.
* ``riskiest_first_chains``: ``count`` chains of ``length`` parts, each part needed, each with
  one fit, onto the base or the chain's previous part, with probabilities increasing along
  every chain. Every failure is a dead end, so every complete policy succeeds with the
  product of all probabilities, and the fewest expected attempts come from testing in
  increasing probability (Smith's ratio rule ``cost / (1 - p)`` with unit costs), an order
  the chains allow: ``sum_k prod_{l<k} p_(l)`` over the probabilities sorted increasing.
  Reaching it interleaves the chains.

``uncertain_tree`` is the other kind a user meets, with no closed form: a synthetic object
(``synthetic.py``: a random tree with alternative sockets) with a few uncertain fits among
those that matter. ``documents`` writes an object and its model as the files a user gives
``causalplan plan``.
"""

from __future__ import annotations

import dataclasses
import math
import random
from dataclasses import dataclass, field

from causalplan.causal.diagnostics import Location
from causalplan.causal.model import CausalModel, Labelling
from causalplan.causal.rules import Rule, parse_rule
from causalplan.comparison.synthetic import object_document, synthetic_task
from causalplan.objects.model import AssemblyObject, Connector, Fit, Part, Requirement
from causalplan.pddl.task import PlanningTask, build_task
from causalplan.planners.mdp.model import relevant_fits

GOAL = "light"
BASE_FUNCTION = "provide power"
_PEG = ("peg", "peg 6 mm")


@dataclass(frozen=True)
class KnownOptimum:
    """A task with its optimum worked out in closed form (``attempts`` None: not in closed form)."""

    task: PlanningTask
    success_probability: float
    expected_attempts: float | None = None


def _rules(texts: list[str]) -> tuple[Rule, ...]:
    rules: list[Rule] = []
    for number, text in enumerate(texts, start=1):
        rule, problems = parse_rule(text, number, Location(rule=number))
        if rule is None:  # pragma: no cover - the texts of this module are always well-formed
            raise AssertionError(f"rule {text!r} does not parse: {problems}")
        rules.append(rule)
    return tuple(rules)


def _chained_goal(ready: list[str]) -> list[str]:
    """Return rules making the goal from every ``ready`` effect, chained two at a time (nested ANDs)."""
    texts: list[str] = []
    previous = ready[0]
    for number, effect in enumerate(ready[1:], start=2):
        texts.append(f"{previous} AND {effect} CAUSES stage {number}")
        previous = f"stage {number}"
    texts.append(f"{previous} AND {BASE_FUNCTION} CAUSES {GOAL}")
    return texts


def _plug(part_id: str, name: str, connectors: tuple[str, ...]) -> Part:
    return Part(part_id, name, tuple(Connector(connector, *_PEG) for connector in connectors))


def _chance(rng: random.Random, low: float, high: float) -> float:
    return round(rng.uniform(low, high), 2)


@dataclass
class _Lamp:
    """A lamp being built: the base with one socket per group, and the parts, fits and rules added to it."""

    groups: int
    parts: list[Part] = field(default_factory=list)
    fits: list[Fit] = field(default_factory=list)
    mechanism: list[Requirement] = field(default_factory=list)
    functions: dict[str, tuple[str, ...]] = field(default_factory=lambda: {"base": (BASE_FUNCTION,)})
    texts: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.parts.append(_plug("base", "base", tuple(f"socket_{j}" for j in range(1, self.groups + 1))))

    def task(self, ready: list[str], obj_id: str, name: str, description: str, explanation: str) -> PlanningTask:
        """Return the task: the goal made from every ``ready`` effect, the model's rules, the object."""
        obj = AssemblyObject(
            id=obj_id,
            name=name,
            category="electric",
            goal=GOAL,
            description=description,
            base="base",
            parts=tuple(self.parts),
            fits=tuple(self.fits),
            mechanism=tuple(self.mechanism),
            mechanism_explanation=explanation,
        )
        model = CausalModel(Labelling(obj.id, self.functions), GOAL, _rules([*self.texts, *_chained_goal(ready)]))
        return build_task(model, obj)


def independent_components(count: int, seed: int = 0) -> KnownOptimum:
    """Return ``count`` independent five-part components (see the module's docstring) and their optimum."""
    rng = random.Random(f"components/{count}/{seed}")
    lamp = _Lamp(count)
    optimum = 1.0
    for j in range(1, count + 1):
        h, x, y, u, v = (f"c{j:02d}_{name}" for name in ("h", "x", "y", "u", "v"))
        p_h, p_v = _chance(rng, 0.85, 0.99), _chance(rng, 0.7, 0.99)
        p_x1, p_x2 = _chance(rng, 0.5, 0.9), _chance(rng, 0.5, 0.9)
        p_y, p_u2, p_u = _chance(rng, 0.5, 0.9), _chance(rng, 0.5, 0.9), _chance(rng, 0.3, 0.6)
        lamp.parts += [
            _plug(h, f"holder {j}", ("plug", "s1", "s2", "s3", "s4", "s5")),
            _plug(x, f"switch {j}", ("plug_a", "plug_b")),
            _plug(y, f"cable {j}", ("plug",)),
            _plug(u, f"spare cable {j}", ("plug",)),
            _plug(v, f"lens {j}", ("plug",)),
        ]
        lamp.fits += [
            Fit(f"{h}_on_base", "insert", h, "plug", "base", f"socket_{j}", p_h),
            Fit(f"{x}_a", "plug", x, "plug_a", h, "s1", p_x1),
            Fit(f"{x}_b", "plug", x, "plug_b", h, "s2", p_x2),
            Fit(f"{y}_shared", "connect", y, "plug", h, "s3", p_y),
            Fit(f"{u}_shared", "connect", u, "plug", h, "s3", p_u),
            Fit(f"{u}_own", "connect", u, "plug", h, "s4", p_u2),
            Fit(f"{v}_on_h", "insert", v, "plug", h, "s5", p_v),
        ]
        lamp.mechanism += [
            Requirement((f"{h}_on_base",), f"holder {j} is on the base"),
            Requirement((f"{x}_a", f"{x}_b"), f"switch {j} is plugged in"),
            Requirement((f"{y}_shared", f"{u}_shared", f"{u}_own"), f"a cable of component {j} is connected"),
            Requirement((f"{v}_on_h",), f"lens {j} is in"),
        ]
        lamp.functions |= {
            h: (f"hold component {j}",),
            x: (f"switch current {j}",),
            y: (f"carry current {j}",),
            u: (f"carry spare current {j}",),
            v: (f"focus light {j}",),
        }
        lamp.texts += [
            f"{BASE_FUNCTION} AND hold component {j} AND switch current {j} AND focus light {j} "
            f"CAUSES circuit {j} is closed",
            f"carry current {j} CAUSES current {j} flows",
            f"carry spare current {j} CAUSES current {j} flows",
            f"circuit {j} is closed AND current {j} flows CAUSES component {j} works",
        ]
        optimum *= p_h * (1 - (1 - p_x1) * (1 - p_x2)) * (1 - (1 - p_y) * (1 - p_u2)) * p_v
    task = lamp.task(
        [f"component {j} works" for j in range(1, count + 1)],
        f"components_{count}_{seed}",
        f"lamp of {count} independent components (seed {seed})",
        f"{count} five-part components, each on its own socket of the base.",
        "Every component works: its holder, switch and lens in, and one of its cables.",
    )
    return KnownOptimum(task, optimum)


def cyclic_components(count: int, seed: int = 0) -> KnownOptimum:
    """Return ``count`` independent components whose four parts share their holder's sockets in a cycle.

    In component ``j`` a holder ``h`` goes onto the base; parts ``a, b, c, d`` each fit two of
    the holder's four sockets (``a``: 1 or 2, ``b``: 2 or 3, ``c``: 3 or 4, ``d``: 4 or 1), and
    all four are needed. Each part has one plug, so a failure is a dead end, and only the two
    rotations fill every socket: the best a component can do is ``p_h`` times the more reliable
    rotation's product. A greedy choice that looks one step ahead can start the other way
    round half-way and strand the last part.
    """
    rng = random.Random(f"cyclic/{count}/{seed}")
    lamp = _Lamp(count)
    optimum = 1.0
    for j in range(1, count + 1):
        h = f"r{j:02d}_h"
        p_h = _chance(rng, 0.85, 0.99)
        lamp.parts.append(_plug(h, f"ring {j}", ("plug", "s1", "s2", "s3", "s4")))
        lamp.fits.append(Fit(f"{h}_on_base", "insert", h, "plug", "base", f"socket_{j}", p_h))
        lamp.mechanism.append(Requirement((f"{h}_on_base",), f"ring {j} is on the base"))
        lamp.functions[h] = (f"hold ring {j}",)
        rotations = [1.0, 1.0]
        for k, name in enumerate("abcd"):
            part = f"r{j:02d}_{name}"
            lamp.parts.append(_plug(part, f"contact {j}{name}", ("plug",)))
            own, next_one = k + 1, (k + 1) % 4 + 1
            chances = (_chance(rng, 0.6, 0.95), _chance(rng, 0.6, 0.95))
            lamp.fits += [
                Fit(f"{part}_s{own}", "clip", part, "plug", h, f"s{own}", chances[0]),
                Fit(f"{part}_s{next_one}", "clip", part, "plug", h, f"s{next_one}", chances[1]),
            ]
            rotations = [rotations[0] * chances[0], rotations[1] * chances[1]]
            lamp.mechanism.append(Requirement((f"{part}_s{own}", f"{part}_s{next_one}"), f"contact {j}{name} is in"))
            lamp.functions[part] = (f"touch ring {j} {name}",)
        lamp.texts.append(
            f"hold ring {j} AND "
            + " AND ".join(f"touch ring {j} {name}" for name in "abcd")
            + f" CAUSES ring {j} conducts"
        )
        optimum *= p_h * max(rotations)
    task = lamp.task(
        [f"ring {j} conducts" for j in range(1, count + 1)],
        f"rings_{count}_{seed}",
        f"lamp of {count} rings of contacts (seed {seed})",
        f"{count} rings, each a holder on its own socket of the base with four contacts around it.",
        "Every ring is on the base with its four contacts in.",
    )
    return KnownOptimum(task, optimum)


def riskiest_first_chains(count: int, length: int, seed: int = 0) -> KnownOptimum:
    """Return ``count`` chains of ``length`` needed parts (see the module's docstring) and their optimum."""
    rng = random.Random(f"chains/{count}/{length}/{seed}")
    lamp = _Lamp(count)
    chances: list[float] = []
    for c in range(1, count + 1):
        along = sorted(_chance(rng, 0.6, 0.999) for _ in range(length))
        holder, socket = "base", f"socket_{c}"
        for k, p in enumerate(along, start=1):
            part = f"k{c:02d}_{k:02d}"
            lamp.parts.append(_plug(part, f"link {c}.{k}", ("plug", "socket")))
            lamp.fits.append(Fit(f"{part}_in", "insert", part, "plug", holder, socket, p))
            lamp.mechanism.append(Requirement((f"{part}_in",), f"link {c}.{k} is in"))
            lamp.functions[part] = (f"pass current {c} {k}",)
            holder, socket = part, "socket"
        lamp.texts.append(
            " AND ".join(f"pass current {c} {k}" for k in range(1, length + 1)) + f" CAUSES chain {c} conducts"
        )
        chances += along
    task = lamp.task(
        [f"chain {c} conducts" for c in range(1, count + 1)],
        f"chains_{count}x{length}_{seed}",
        f"lamp of {count} chains of {length} links (seed {seed})",
        f"{count} chains of {length} links, each chain on its own socket of the base.",
        "Every link of every chain is in.",
    )
    ordered = sorted(chances)
    attempts = sum(math.prod(ordered[:k]) for k in range(len(ordered)))
    return KnownOptimum(task, math.prod(chances), attempts)


def with_probabilities(task: PlanningTask, seed: int, low: float = 0.7) -> PlanningTask:
    """Return the task with every fit's probability drawn (seeded) in [``low``, 1], to two places."""
    rng = random.Random(seed)
    fits = tuple(dataclasses.replace(fit, probability=round(rng.uniform(low, 1.0), 2)) for fit in task.obj.fits)
    return dataclasses.replace(task, obj=dataclasses.replace(task.obj, fits=fits))


def uncertain_tree(n_parts: int, uncertain: int, seed: int = 0) -> PlanningTask:
    """Return the synthetic object of this size and seed with ``uncertain`` of the fits that matter in [0.6, 0.95]."""
    task = synthetic_task(n_parts, seed)
    rng = random.Random(f"uncertain/{n_parts}/{uncertain}/{seed}")
    chosen = set(rng.sample(sorted(fit.id for fit in relevant_fits(task)), uncertain))
    fits = tuple(
        dataclasses.replace(fit, probability=_chance(rng, 0.6, 0.95)) if fit.id in chosen else fit
        for fit in task.obj.fits
    )
    return dataclasses.replace(task, obj=dataclasses.replace(task.obj, fits=fits))


def documents(task: PlanningTask) -> tuple[dict[str, object], dict[str, object]]:
    """Return the task's object and model as the documents a user writes (object file, model file)."""
    model_document: dict[str, object] = {
        "object": task.obj.id,
        "goal": task.goal,
        "functions": {part: list(labels) for part, labels in task.labelling.functions.items()},
        "rules": [rule.text for rule in task.rules],
    }
    return object_document(task.obj), model_document
