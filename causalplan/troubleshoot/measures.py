"""The measures the field reports, per strategy: expected actions, the worst case, the reward share.

Every strategy's policy is scored under the catalog's fault priors (the world's), whatever
prior it was solved under. The reward follows Basu et al. (Frontiers in AI, 2025): -1 per
action plus a repair bonus when the object works again, as a share of the most a robot that
knew the broken part could get (its fewest actions); the share is averaged over the fault
locations, each counted once, as they average over runs per location.
"""

from __future__ import annotations

from dataclasses import dataclass

from causalplan.objects.model import AssemblyObject
from causalplan.troubleshoot.episode import Episode, run_episode
from causalplan.troubleshoot.solver import Policy

REPAIR_BONUS = 20.0
"""The reward for the repair; above every catalog object's longest episode, so rewards stay positive."""


@dataclass(frozen=True)
class FaultResult:
    """One fault location under one strategy: the actions it took, the fewest possible, the reward share."""

    part: str
    probability: float
    actions: int
    fewest_actions: int
    reward_share: float

    def as_dict(self) -> dict[str, object]:
        return {
            "part": self.part,
            "probability": self.probability,
            "actions": self.actions,
            "fewest_actions": self.fewest_actions,
            "reward_share": round(self.reward_share, 6),
        }


@dataclass(frozen=True)
class StrategyResult:
    """One strategy on one object: its own expectation, and its measures under the catalog's priors."""

    strategy: str
    own_expected_actions: float
    faults: tuple[FaultResult, ...]

    @property
    def expected_actions(self) -> float:
        """Return the expected actions to the repair under the catalog's fault priors."""
        return sum(fault.probability * fault.actions for fault in self.faults)

    @property
    def worst_actions(self) -> int:
        return max(fault.actions for fault in self.faults)

    @property
    def reward_share(self) -> float:
        """Return the reward as a share of the maximum, averaged over the fault locations."""
        return sum(fault.reward_share for fault in self.faults) / len(self.faults)

    def as_dict(self) -> dict[str, object]:
        return {
            "expected_actions": round(self.expected_actions, 6),
            "worst_actions": self.worst_actions,
            "reward_share": round(self.reward_share, 6),
            "own_expected_actions": round(self.own_expected_actions, 6),
            "faults": {fault.part: fault.as_dict() for fault in self.faults},
        }


def fewest_actions(policy: Policy, part: str) -> int:
    """Return the fewest actions that repair the object when the broken part is known to be ``part``."""
    known = (1 << policy.structure.index(part), 0)
    return round(policy.value(known, policy.graph.assembled))


def reward_share(actions: int, fewest: int, bonus: float = REPAIR_BONUS) -> float:
    """Return (bonus - actions) / (bonus - fewest): 1 for a repair in the fewest actions."""
    return (bonus - actions) / (bonus - fewest)


def score(policy: Policy, obj: AssemblyObject, bonus: float = REPAIR_BONUS) -> tuple[StrategyResult, list[Episode]]:
    """Return ``policy``'s measures on ``obj`` under its catalog priors, and its episode for each fault."""
    results: list[FaultResult] = []
    episodes: list[Episode] = []
    for fault in obj.faults:
        episode = run_episode(policy, fault.part)
        fewest = fewest_actions(policy, fault.part)
        share = reward_share(episode.actions, fewest, bonus)
        results.append(FaultResult(fault.part, fault.probability, episode.actions, fewest, share))
        episodes.append(episode)
    return StrategyResult(policy.suspicion.strategy, policy.expected_actions(), tuple(results)), episodes
