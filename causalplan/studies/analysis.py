"""The analysis the paper's far-generalization experiment needs, computed from an export's trials.

The paper predicts: trained on one category, models transfer more to a test object of that
category than to one of the other (near beats far); trained on both categories, they transfer
to both. ``analyse`` gives the transfer rate of every condition x test object with a Wilson
interval (the one rates table, ``rates.rate_table``), Fisher's exact tests of those predictions
(Holm-corrected over the family), a logistic GEE with the participant as cluster, failure
reasons per condition, the paper's misconception per participant, the conclusions in plain
words with the sample behind each, and (given a mapping scorer) the rates again without the
transfers that rest on implausible mappings (``sensitivity``).
A trial's outcome is 1 when its model transferred and 0 when it failed or was invalid;
undecided trials (the planner timed out) and excluded participants are counted, not analysed.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from causalplan.objects.catalog import Catalog
from causalplan.studies.far_generalization import BOTH_CATEGORIES, ONE_CATEGORY, prediction_tests
from causalplan.studies.misconceptions import Misconception, MisconceptionCheck, check_misconceptions
from causalplan.studies.rates import Rate, RateTable, rate_table, share, training_spans
from causalplan.studies.sensitivity import MappingScorer, Sensitivity, sensitivity
from causalplan.studies.statistics import ClusteredModel, Comparison, Proportion, clustered_logistic, fisher, holm
from causalplan.studies.trials import Study, TrialRow, read_study

SIGNIFICANCE = 0.05


@dataclass(frozen=True)
class Analysis:
    """Everything ``analyse`` computed; ``as_dict`` is the JSON the command writes."""

    rows: tuple[TrialRow, ...]
    table: RateTable
    comparisons: tuple[Comparison, ...]
    clustered: ClusteredModel
    reasons: dict[str, dict[str, int]]
    misconceptions: dict[str, tuple[Misconception, ...]]
    conclusions: tuple[str, ...]
    misconceptions_not_checked: dict[str, str] = field(default_factory=dict)
    """Participant id -> why their model could not be checked for the misconception."""
    sensitivity: Sensitivity | None = None
    """The rates without transfers resting on implausible mappings (None: no scorer was given)."""

    @property
    def rates(self) -> tuple[Rate, ...]:
        return self.table.rates

    @property
    def analysed(self) -> list[TrialRow]:
        return [row for row in self.rows if not row.excluded and row.outcome is not None]

    def as_dict(self) -> dict[str, object]:
        left_out = self.table.left_out
        return {
            "trials": left_out.trials,
            "analysed_trials": left_out.analysed_trials,
            "undecided_trials": left_out.undecided_trials,
            "excluded_trials": left_out.excluded_trials,
            "excluded_participants": sorted(left_out.excluded_participants),
            "exclusion_reasons": left_out.reasons(),
            "left_out": left_out.says(),
            "rates": [rate.as_dict() for rate in self.rates],
            "comparisons": [comparison.as_dict() for comparison in self.comparisons],
            "clustered_model": self.clustered.as_dict(),
            "failure_reasons": self.reasons,
            "misconceptions": {
                participant: [found.as_dict() for found in items] for participant, items in self.misconceptions.items()
            },
            "misconceptions_not_checked": self.misconceptions_not_checked,
            "conclusions": list(self.conclusions),
            "mapping_plausibility": self.sensitivity.as_dict() if self.sensitivity is not None else None,
        }


def _comparisons(rows: Sequence[TrialRow], spans: dict[str, str]) -> list[Comparison]:
    """Return the family of tests of the paper's two predictions (before Holm's correction)."""
    found = []
    conditions = list(dict.fromkeys(row.condition for row in rows))
    for condition in conditions:
        mine = [row for row in rows if row.condition == condition]
        if spans[condition] == ONE_CATEGORY:
            same = [row for row in mine if row.trained_category]
            other = [row for row in mine if not row.trained_category]
            if same and other:
                found.append(
                    fisher(
                        f"{condition}: same-category vs other-category test objects",
                        ("same category", share(same)),
                        ("other category", share(other)),
                        "greater",
                    )
                )
            continue
        tests = sorted({row.test_object for row in mine})
        for index, first in enumerate(tests):
            for second in tests[index + 1 :]:
                found.append(
                    fisher(
                        f"{condition}: {first} vs {second}",
                        (first, share([row for row in mine if row.test_object == first])),
                        (second, share([row for row in mine if row.test_object == second])),
                        "two-sided",
                    )
                )
        for other_condition in conditions:
            if spans[other_condition] != ONE_CATEGORY:
                continue
            untrained = {
                row.test_object for row in rows if row.condition == other_condition and not row.trained_category
            }
            for test in sorted(untrained & set(tests)):
                found.append(
                    fisher(
                        f"{test}: {condition} vs {other_condition}",
                        (condition, share([row for row in mine if row.test_object == test])),
                        (
                            other_condition,
                            share([r for r in rows if r.condition == other_condition and r.test_object == test]),
                        ),
                        "greater",
                    )
                )
    return holm(found)


def _percent(proportion: Proportion) -> str:
    if proportion.rate is None or proportion.low is None or proportion.high is None:
        return "no trials"
    return (
        f"{proportion.successes}/{proportion.trials} ({proportion.rate:.0%}, "
        f"95% CI {proportion.low:.0%}-{proportion.high:.0%})"
    )


def _conclusion(comparison: Comparison) -> str:
    assert comparison.p_holm is not None
    significant = comparison.p_holm < SIGNIFICANCE
    if comparison.alternative == "greater":
        verdict = "the prediction holds" if significant else "the prediction is not shown at this sample size"
        if not significant and comparison.odds_ratio_interval[1] < 1:
            verdict = "the opposite of the prediction: the first group transferred less"
    else:
        verdict = (
            "they differ, so models did not transfer equally to both"
            if significant
            else "no reliable difference, consistent with transfer to both"
        )
    low, high = comparison.odds_ratio_interval
    odds = (
        f"odds ratio {comparison.odds_ratio:.2f} (95% CI {low:.2f}-{high:.2f})"
        if all(math.isfinite(value) for value in (comparison.odds_ratio, low, high))
        else "odds ratio not estimable from these counts"
    )
    return (
        f"{comparison.name}: {_percent(comparison.first_share)} vs {_percent(comparison.second_share)}; "
        f"Fisher {comparison.alternative} p = {comparison.p_value:.3g}, Holm p = {comparison.p_holm:.3g}, "
        f"{odds}: {verdict}."
    )


def _misconceptions(
    rows: Sequence[TrialRow], catalog: Catalog
) -> tuple[dict[str, tuple[Misconception, ...]], dict[str, str]]:
    """Return each participant's misconceptions (those with any), and why a participant's model was not checked."""
    checked: dict[str, MisconceptionCheck] = {}
    for row in rows:
        if row.participant_id in checked:
            continue
        if row.model is None:
            checked[row.participant_id] = MisconceptionCheck(not_checked="the export has no model for the participant")
            continue
        checked[row.participant_id] = check_misconceptions(row.model, catalog, row.training_objects)
    found = {participant: check.found for participant, check in checked.items() if check.found}
    skipped = {participant: check.not_checked for participant, check in checked.items() if check.not_checked}
    return found, skipped


def analyse(study: Study, catalog: Catalog) -> Analysis:
    """Return the study's analysis: rates, tests, the clustered model, reasons, misconceptions, conclusions."""
    rows = study.rows
    included = [row for row in rows if not row.excluded]
    decided = [row for row in included if row.outcome is not None]
    spans = training_spans(included, catalog)
    comparisons = holm([*_comparisons(decided, spans), *prediction_tests(decided, catalog)]) if decided else []
    clustered = clustered_logistic(
        [row.outcome or 0 for row in decided],
        {
            "other_category_test": [0 if row.trained_category else 1 for row in decided],
            "trained_on_both": [1 if spans[row.condition] == BOTH_CATEGORIES else 0 for row in decided],
        },
        [row.participant_id for row in decided],
    )
    reasons: dict[str, dict[str, int]] = {}
    for condition in dict.fromkeys(row.condition for row in included):
        counts = Counter(
            code
            for row in included
            if row.condition == condition and row.outcome == 0
            for code in set(row.reason_codes)
        )
        reasons[condition] = dict(counts.most_common())
    found, not_checked = _misconceptions(included, catalog)
    conclusions = [_conclusion(comparison) for comparison in comparisons]
    if not comparisons:
        conclusions.append("No test of the predictions could be made: each needs two groups of decided trials.")
    for effect in clustered.effects:
        conclusions.append(
            f"Logistic GEE ({clustered.trials} trials, {clustered.participants} participants): {effect.name} has an "
            f"odds ratio of {effect.odds_ratio:.2f} (95% CI {effect.interval[0]:.2f}-{effect.interval[1]:.2f}, "
            f"p = {effect.p_value:.3g})."
        )
    if clustered.problem:
        conclusions.append(f"Logistic GEE not reported: {clustered.problem}.")
    participants = len({row.participant_id for row in included})
    checked = participants - len(not_checked)
    if found:
        conclusions.append(
            f"{len(found)} of {checked} participants whose models were checked made a function the true "
            "mechanism does not need a necessary cause (the paper's 'diffuse light' misconception)."
        )
    if not_checked:
        why = "; ".join(f"{reason} ({count})" for reason, count in Counter(not_checked.values()).most_common())
        conclusions.append(
            f"The misconception was not looked for in {len(not_checked)} of {participants} participants' models: {why}."
        )
    return Analysis(
        rows,
        rate_table(study, catalog),
        tuple(comparisons),
        clustered,
        reasons,
        found,
        tuple(conclusions),
        not_checked,
    )


def analyse_export(export: Mapping[str, Any], catalog: Catalog, scorer: MappingScorer | None = None) -> Analysis:
    """Return the analysis of an experiment export (``causalplan analyze`` and the research page alike).

    ``scorer``: how plausible each transfer's mapping is; the analysis then has the rates without
    the implausible ones too (``sensitivity``).
    """
    study = read_study(export, catalog)
    analysis = analyse(study, catalog)
    if scorer is None:
        return analysis
    return replace(analysis, sensitivity=sensitivity(study, catalog, scorer))
