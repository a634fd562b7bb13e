"""The statistics of a transfer study, from statsmodels and scipy: Wilson intervals, Fisher's
exact tests with Holm's correction, odds ratios, and a logistic GEE with the participant as cluster.

Each function takes counts or 0/1 outcomes and returns a small frozen value that says what was
computed and on how many trials, so the report never prints a number it did not compute.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace

CONFIDENCE = 0.95


@dataclass(frozen=True)
class Proportion:
    """A share of successes with its 95% Wilson interval."""

    successes: int
    trials: int
    low: float | None
    high: float | None

    @property
    def rate(self) -> float | None:
        return self.successes / self.trials if self.trials else None

    def as_dict(self) -> dict[str, object]:
        return {
            "successes": self.successes,
            "trials": self.trials,
            "rate": self.rate,
            "interval": [self.low, self.high],
        }


def wilson(successes: int, trials: int) -> Proportion:
    """Return the share with its Wilson score interval (no interval without trials)."""
    if trials == 0:
        return Proportion(0, 0, None, None)
    from statsmodels.stats.proportion import proportion_confint

    low, high = proportion_confint(successes, trials, alpha=1 - CONFIDENCE, method="wilson")
    return Proportion(successes, trials, float(low), float(high))


@dataclass(frozen=True)
class Comparison:
    """Fisher's exact test of two shares, with the odds ratio and, once corrected, Holm's p value."""

    name: str
    first: str
    second: str
    first_share: Proportion
    second_share: Proportion
    alternative: str
    p_value: float
    odds_ratio: float
    odds_ratio_interval: tuple[float, float]
    p_holm: float | None = None

    def as_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "first": self.first,
            "second": self.second,
            "first_share": self.first_share.as_dict(),
            "second_share": self.second_share.as_dict(),
            "alternative": self.alternative,
            "p_value": self.p_value,
            "p_holm": self.p_holm,
            "odds_ratio": self.odds_ratio,
            "odds_ratio_interval": list(self.odds_ratio_interval),
            "n": self.first_share.trials + self.second_share.trials,
        }


def fisher(name: str, first: tuple[str, Proportion], second: tuple[str, Proportion], alternative: str) -> Comparison:
    """Return Fisher's exact test of first's share against second's (``greater``: first is higher).

    The odds ratio and its interval come from the 2x2 table with 0.5 added to every cell when
    one is empty (Haldane's correction), so a perfect split still gives a finite estimate.
    """
    from scipy.stats import fisher_exact
    from statsmodels.stats.contingency_tables import Table2x2

    (first_name, a), (second_name, b) = first, second
    table = [[a.successes, a.trials - a.successes], [b.successes, b.trials - b.successes]]
    p_value = float(fisher_exact(table, alternative=alternative).pvalue)
    odds = Table2x2(table, shift_zeros=True)
    low, high = odds.oddsratio_confint(alpha=1 - CONFIDENCE)
    return Comparison(
        name, first_name, second_name, a, b, alternative, p_value, float(odds.oddsratio), (float(low), float(high))
    )


def holm(comparisons: Sequence[Comparison]) -> list[Comparison]:
    """Return the comparisons with Holm-corrected p values over the whole family."""
    if not comparisons:
        return []
    from statsmodels.stats.multitest import multipletests

    corrected = multipletests([c.p_value for c in comparisons], method="holm")[1]
    return [replace(c, p_holm=float(p)) for c, p in zip(comparisons, corrected, strict=True)]


@dataclass(frozen=True)
class Effect:
    """One predictor of a logistic model: its odds ratio with a 95% interval and p value."""

    name: str
    odds_ratio: float
    interval: tuple[float, float]
    p_value: float

    def as_dict(self) -> dict[str, object]:
        return {**asdict(self), "interval": list(self.interval)}


@dataclass(frozen=True)
class ClusteredModel:
    """A logistic GEE (exchangeable correlation within participant), or why it could not be fitted."""

    formula: str
    trials: int
    participants: int
    effects: tuple[Effect, ...]
    problem: str | None = None

    def as_dict(self) -> dict[str, object]:
        return {
            "model": "logistic GEE, exchangeable correlation within participant, robust standard errors",
            "formula": self.formula,
            "trials": self.trials,
            "participants": self.participants,
            "effects": [effect.as_dict() for effect in self.effects],
            "problem": self.problem,
        }


MAX_LOG_ODDS = 700.0
"""Beyond this log odds ratio ``math.exp`` overflows: the fit has separated, and gives no number worth reporting."""


def clustered_logistic(
    outcomes: Sequence[int], predictors: dict[str, Sequence[int]], clusters: Sequence[str]
) -> ClusteredModel:
    """Fit ``logit P(outcome) = b0 + sum(b_k * predictor_k)`` by GEE with the clusters as groups.

    Predictors that do not vary are left out (they cannot be estimated); a fit that does not
    converge or separates perfectly is reported as a problem rather than as numbers.
    """
    import numpy as np
    import statsmodels.api as sm
    from statsmodels.tools.sm_exceptions import ConvergenceWarning, PerfectSeparationWarning

    usable = {name: values for name, values in predictors.items() if len(set(values)) > 1}
    formula = "transferred ~ 1" + "".join(f" + {name}" for name in usable)
    participants = len(set(clusters))
    if len(set(outcomes)) < 2 or not usable:
        problem = "every trial has the same outcome" if len(set(outcomes)) < 2 else "no predictor varies"
        return ClusteredModel(formula, len(outcomes), participants, (), problem)
    exog = np.column_stack([np.ones(len(outcomes)), *(np.asarray(v, dtype=float) for v in usable.values())])
    groups = np.unique(np.asarray(clusters), return_inverse=True)[1]
    model = sm.GEE(
        np.asarray(outcomes, dtype=float),
        exog,
        groups=groups,
        family=sm.families.Binomial(),
        cov_struct=sm.cov_struct.Exchangeable(),
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        warnings.simplefilter("error", PerfectSeparationWarning)
        try:
            fitted = model.fit()
        except (ConvergenceWarning, PerfectSeparationWarning, np.linalg.LinAlgError, ValueError) as exc:
            return ClusteredModel(formula, len(outcomes), participants, (), f"the model could not be fitted: {exc}")
    intervals = np.asarray(fitted.conf_int(alpha=1 - CONFIDENCE))
    estimates = np.concatenate([np.asarray(fitted.params), intervals.ravel(), np.asarray(fitted.pvalues)])
    if not np.all(np.isfinite(estimates)):
        # Too few participants (or no variation within them) for robust errors: say so, never print nan.
        return ClusteredModel(
            formula, len(outcomes), participants, (), "its estimates are not finite: too few participants for it"
        )
    effects = []
    for index, name in enumerate(usable, start=1):
        low, high = intervals[index]
        if not all(abs(value) < MAX_LOG_ODDS for value in (fitted.params[index], low, high)):
            # A (quasi-)separated sample: the fit runs off towards infinity without a warning.
            problem = f"the model could not be fitted: {name}'s odds ratio runs off to infinity (too few trials)"
            return ClusteredModel(formula, len(outcomes), participants, (), problem)
        effects.append(
            Effect(name, math.exp(fitted.params[index]), (math.exp(low), math.exp(high)), float(fitted.pvalues[index]))
        )
    return ClusteredModel(formula, len(outcomes), participants, tuple(effects))
