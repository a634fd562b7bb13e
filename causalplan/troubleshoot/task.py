"""A troubleshooting task: a broken object, the strategies' priors, their policies, episodes and table."""

from __future__ import annotations

from dataclasses import dataclass, field

from causalplan.causal.labels import closest
from causalplan.causal.model import CausalModel, Labelling
from causalplan.objects.model import AssemblyObject
from causalplan.troubleshoot.episode import Episode, run_episode
from causalplan.troubleshoot.errors import FaultNotNeededError, NoFaultsError, UnknownFaultPartError
from causalplan.troubleshoot.measures import REPAIR_BONUS, StrategyResult, score
from causalplan.troubleshoot.priors import STRATEGIES, Suspicion, model_suspicion, oracle_suspicion, uniform_suspicion
from causalplan.troubleshoot.solver import MAX_STATES, Policy, solve
from causalplan.troubleshoot.structure import Structure, structure_of


@dataclass
class TroubleshootingTask:
    """One broken object and the priors of the strategies that try to repair it (``model`` only with a model)."""

    obj: AssemblyObject
    structure: Structure
    suspicions: dict[str, Suspicion]
    routes: tuple[frozenset[str], ...] = ()
    """The model's routes to the goal (minimal sets of function labels); empty without a model."""
    max_states: int = MAX_STATES
    _policies: dict[str, Policy] = field(default_factory=dict, repr=False)

    @property
    def strategies(self) -> tuple[str, ...]:
        return tuple(name for name in STRATEGIES if name in self.suspicions)

    def policy(self, strategy: str) -> Policy:
        """Return the exact policy of ``strategy`` (solved once per task)."""
        if strategy not in self._policies:
            self._policies[strategy] = solve(self.structure, self.suspicions[strategy], self.max_states)
        return self._policies[strategy]

    def episode(self, strategy: str, fault: str) -> Episode:
        """Return ``strategy``'s episode on the object broken at ``fault`` (checked first)."""
        check_fault(self.obj, fault)
        return run_episode(self.policy(strategy), fault)

    def table(self, bonus: float = REPAIR_BONUS) -> dict[str, StrategyResult]:
        """Return every strategy's measures under the catalog's fault priors."""
        return {strategy: score(self.policy(strategy), self.obj, bonus)[0] for strategy in self.strategies}


def check_fault(obj: AssemblyObject, part: str) -> None:
    """Raise when ``part`` cannot be the broken part of ``obj``: not one of its parts, or not needed."""
    if part not in obj.part_ids:
        guess = closest(part, list(obj.part_ids))
        hint = f" Did you mean '{guess}'?" if guess else ""
        raise UnknownFaultPartError(
            f"The {obj.name} ({obj.id}) has no part '{part}'; its parts: {', '.join(obj.part_ids)}.{hint}",
            details={"object": obj.id, "part": part},
        )
    if not obj.is_needed(part):
        raise FaultNotNeededError(
            f"The {obj.name}'s true mechanism does not need the {obj.part(part).name} ({part}): with it broken, "
            f"the object still gives {obj.goal}. Choose one of: {', '.join(f.part for f in obj.faults)}.",
            details={"object": obj.id, "part": part},
        )


def troubleshooting_task(
    obj: AssemblyObject,
    model: CausalModel | None = None,
    mapping: Labelling | None = None,
    max_states: int = MAX_STATES,
) -> TroubleshootingTask:
    """Return the task of repairing ``obj``; with a model (and its mapping on a new object), the ``model`` strategy.

    NoFaultsError when the catalog lists no faults for ``obj``; MappingMismatchError when the
    model's (or mapping's) functions are another object's, or reach no goal on this one.
    """
    if not obj.faults:
        raise NoFaultsError(
            f"The {obj.name} ({obj.id}) lists no faults in its catalog file, so it cannot be troubleshot. "
            "Add a 'faults:' section (see docs/troubleshooting.md).",
            details={"object": obj.id},
        )
    structure = structure_of(obj)
    suspicions: dict[str, Suspicion] = {}
    routes: tuple[frozenset[str], ...] = ()
    if model is not None:
        believed = model_suspicion(model.rules, model.goal_key, mapping or model.labelling, obj)
        suspicions["model"] = believed.suspicion
        routes = believed.routes
    suspicions["uniform"] = uniform_suspicion(obj)
    suspicions["oracle"] = oracle_suspicion(obj)
    return TroubleshootingTask(obj, structure, suspicions, routes, max_states)
