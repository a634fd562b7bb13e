"""Who is suspected, and how much: the three strategies' priors over the broken part.

- ``model``: a person's causal model (with a step-3 mapping on a new object). A part is a
  suspect when it carries a function that some route to the goal needs, in proportion to the
  number of routes that need it; a route is a minimal set of functions that the rules turn
  into the goal. Parts the model leaves out get weight 0.
- ``uniform``: no model; every part is equally suspect (the floor).
- ``oracle``: the catalog's fault priors (the best a robot can do).

A weight of 0 does not rule a part out: once every part with weight has been cleared, the
remaining parts are suspected equally (``Suspicion.share``), so every policy still repairs
every fault.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from causalplan.causal.model import Labelling
from causalplan.causal.rules import Rule
from causalplan.objects.model import AssemblyObject
from causalplan.troubleshoot.errors import MappingMismatchError, TroubleshootError
from causalplan.troubleshoot.structure import bits

STRATEGIES = ("model", "uniform", "oracle")
MAX_ROUTES = 10_000


@dataclass(frozen=True)
class Suspicion:
    """A strategy's prior over which part is broken: a weight per part (in the catalog's order)."""

    strategy: str
    weights: tuple[float, ...]

    def mass(self, mask: int) -> float:
        """Return the total weight of the parts in ``mask``."""
        return sum(self.weights[index] for index in bits(mask))

    def share(self, part: int, among: int) -> float:
        """Return the probability that the broken part is ``part``, given that it is one of ``among``.

        By weight while any part of ``among`` has weight; equally among them once none has.
        """
        total = self.mass(among)
        if total > 0:
            return self.weights[part] / total
        return 1.0 / among.bit_count()

    def as_dict(self, parts: Sequence[str]) -> dict[str, float]:
        """Return each part's prior (weights normalised to sum to 1)."""
        total = sum(self.weights) or 1.0
        return {part: weight / total for part, weight in zip(parts, self.weights, strict=True)}


def uniform_suspicion(obj: AssemblyObject) -> Suspicion:
    return Suspicion("uniform", tuple(1.0 for _ in obj.parts))


def oracle_suspicion(obj: AssemblyObject) -> Suspicion:
    """Return the catalog's fault priors (0 for the parts it does not list)."""
    priors = {fault.part: fault.probability for fault in obj.faults}
    return Suspicion("oracle", tuple(priors.get(part, 0.0) for part in obj.part_ids))


def _minimal(sets: Iterable[frozenset[str]]) -> list[frozenset[str]]:
    """Return the sets none of whose proper subsets is among them, smallest first, then alphabetically."""
    unique = sorted(set(sets), key=lambda item: (len(item), sorted(item)))
    kept: list[frozenset[str]] = []
    for candidate in unique:
        if not any(other <= candidate for other in kept):
            kept.append(candidate)
    return kept


def goal_routes(rules: Sequence[Rule], goal_key: str, functions: set[str]) -> list[frozenset[str]]:
    """Return the minimal sets of ``functions`` (normalised labels) that the rules turn into the goal.

    A node is produced by any rule with that effect whose causes are all produced (OR over
    rules, AND within one), or is itself a function. A rule that runs in a circle back to a
    node being worked out adds no route through it.
    """
    by_effect: dict[str, list[Rule]] = {}
    for rule in rules:
        by_effect.setdefault(rule.effect_key, []).append(rule)
    done: dict[tuple[str, frozenset[str]], list[frozenset[str]]] = {}

    def routes(node: str, visiting: frozenset[str]) -> list[frozenset[str]]:
        # Keyed by what is being worked out too: a route cut at a circle depends on where it started.
        key = (node, visiting)
        if key in done:
            return done[key]
        inside = visiting | {node}
        found: list[frozenset[str]] = [frozenset({node})] if node in functions else []
        for rule in by_effect.get(node, []):
            if rule.cause_keys & inside:
                continue
            combined: list[frozenset[str]] = [frozenset()]
            for cause in sorted(rule.cause_keys):
                options = routes(cause, inside)
                combined = _minimal(left | right for left in combined for right in options)
                if len(combined) > MAX_ROUTES:
                    raise TroubleshootError(
                        f"The model has more than {MAX_ROUTES} ways to the goal; troubleshooting with it is too large.",
                        details={"limit": MAX_ROUTES},
                    )
            found.extend(combined)
        done[key] = _minimal(found)
        return done[key]

    return routes(goal_key, frozenset())


@dataclass(frozen=True)
class ModelSuspicion:
    """The ``model`` strategy's prior, and the routes to the goal it counts."""

    suspicion: Suspicion
    routes: tuple[frozenset[str], ...]


def model_suspicion(rules: Sequence[Rule], goal_key: str, labelling: Labelling, obj: AssemblyObject) -> ModelSuspicion:
    """Return the prior a causal model (on ``obj``, through ``labelling``) gives each part.

    MappingMismatchError when the labelling is another object's, or when no route to the goal
    uses only functions that ``obj``'s parts carry (the model cannot make this object work).
    """
    if labelling.object_id != obj.id:
        raise MappingMismatchError(
            f"The functions are given for '{labelling.object_id}', not for the {obj.name} ({obj.id}): "
            f"give a step-3 mapping of the {obj.name}'s parts.",
            details={"object": obj.id, "mapping_object": labelling.object_id},
        )
    carriers = labelling.carriers()
    routes = goal_routes(rules, goal_key, set(carriers))
    if not routes:
        raise MappingMismatchError(
            f"Under this mapping no route of the model reaches '{goal_key}' with the functions the {obj.name}'s "
            "parts carry, so the model suspects nothing.",
            details={"object": obj.id, "functions": sorted(carriers)},
        )
    functions_of = {part: {key for key, parts in carriers.items() if part in parts} for part in obj.part_ids}
    weights = tuple(float(sum(1 for route in routes if route & functions_of[part])) for part in obj.part_ids)
    return ModelSuspicion(Suspicion("model", weights), tuple(routes))
