"""A sensitivity analysis of the rates: how they change without transfers that rest on implausible mappings.

A transfer is decided by the planner on the participant's own step-3 mapping; a mapping that
gives an electric function to a match makes an all-electric model "transfer" to the candle.
The caller scores each analysed transfer's mapping (``consensus.plausibility``, which this
stage may not import: it is given as a ``MappingScorer``); transfers scoring under the
scorer's threshold are listed, and the rates are given again without those trials (out of the
numerator and the denominator: they are not counted as fails, since nobody knows what the
participant would have mapped otherwise).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any, Protocol

from causalplan.objects.catalog import Catalog
from causalplan.studies.rates import RateTable, rate_table
from causalplan.studies.trials import Study, TrialRow


class MappingScorer(Protocol):
    """Scores a step-3 mapping onto a test object in [0, 1]; below ``threshold`` it is implausible."""

    threshold: float

    def __call__(self, test_object: str, mapping: Mapping[str, Any]) -> float: ...


@dataclass(frozen=True)
class ImplausibleTransfer:
    """A transfer whose mapping scored under the threshold."""

    trial_id: str
    participant_id: str
    condition: str
    test_object: str
    score: float
    mapping: Mapping[str, Any]

    def as_dict(self) -> dict[str, Any]:
        return {
            "trial_id": self.trial_id,
            "participant_id": self.participant_id,
            "condition": self.condition,
            "test_object": self.test_object,
            "score": self.score,
            "mapping": dict(self.mapping),
        }


@dataclass(frozen=True)
class Sensitivity:
    """The rates with every analysed transfer, and without those resting on implausible mappings."""

    threshold: float
    scored_transfers: int
    implausible: tuple[ImplausibleTransfer, ...]
    without: RateTable

    def as_dict(self) -> dict[str, Any]:
        return {
            "threshold": self.threshold,
            "scored_transfers": self.scored_transfers,
            "implausible_transfers": [item.as_dict() for item in self.implausible],
            "rates_without_implausible": [rate.as_dict() for rate in self.without.rates],
            "says": self.says(),
        }

    def says(self) -> str:
        """Return the sensitivity analysis in one sentence."""
        if not self.implausible:
            return (
                f"Every one of the {self.scored_transfers} analysed transfers rests on a plausible mapping "
                f"(score {self.threshold:g} or more): the rates stand as they are."
            )
        return (
            f"{len(self.implausible)} of {self.scored_transfers} analysed transfers rest on an implausible mapping "
            f"(score under {self.threshold:g}: a function given to a part unlike what that kind of part does); "
            "without those trials the rates are as in the second table."
        )


def _is_analysed_transfer(row: TrialRow) -> bool:
    return not row.excluded and row.outcome == 1


def sensitivity(study: Study, catalog: Catalog, scorer: MappingScorer) -> Sensitivity:
    """Return the study's rates without the analysed transfers whose mapping ``scorer`` finds implausible."""
    implausible = []
    scored = 0
    for row in study.rows:
        if not _is_analysed_transfer(row) or row.mapping is None:
            continue
        scored += 1
        score = scorer(row.test_object, row.mapping)
        if score < scorer.threshold:
            implausible.append(
                ImplausibleTransfer(
                    row.trial_id, row.participant_id, row.condition, row.test_object, score, row.mapping
                )
            )
    dropped = {item.trial_id for item in implausible}
    kept = replace(study, rows=tuple(row for row in study.rows if row.trial_id not in dropped))
    return Sensitivity(scorer.threshold, scored, tuple(implausible), rate_table(kept, catalog))
