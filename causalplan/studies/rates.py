"""The study's one rates table and its one chart: the research page, ``/v1/experiments/{id}/results``
and ``causalplan analyze`` all show these, computed here from the same export.

A rate counts what the paper would report: the analysed trials, that is the decided trials
(transfers, or fails and invalid models) of the participants screening kept. The trials left out
are counted beside it, with why: their participant was excluded by screening, or the planner
could not decide in time (undecided).
"""

from __future__ import annotations

import io
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from causalplan.errors import UnknownObjectError
from causalplan.objects.catalog import Catalog
from causalplan.studies.design import generalization_of
from causalplan.studies.far_generalization import span_of
from causalplan.studies.statistics import Proportion, wilson
from causalplan.studies.trials import Study, TrialRow

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class Rate:
    """How often the analysed models of one condition transferred to one test object, and what was left out."""

    condition: str
    training_span: str | None
    test_object: str
    generalization: str | None
    share: Proportion
    """Transfers out of the analysed trials, with the 95% Wilson interval."""
    undecided: int
    """Trials of included participants the planner could not decide in time (left out)."""
    excluded: int
    """Trials of participants excluded by screening (left out)."""

    @property
    def trials(self) -> int:
        return self.share.trials

    @property
    def transfers(self) -> int:
        return self.share.successes

    @property
    def fails(self) -> int:
        """Return the analysed trials whose model did not transfer (fails or invalid)."""
        return self.share.trials - self.share.successes

    @property
    def rate(self) -> float | None:
        return self.share.rate

    def as_dict(self) -> dict[str, Any]:
        return {
            "condition": self.condition,
            "training_span": self.training_span,
            "test_object": self.test_object,
            "generalization": self.generalization,
            "trials": self.trials,
            "transfers": self.transfers,
            "fails": self.fails,
            "undecided": self.undecided,
            "excluded": self.excluded,
            "rate": self.rate,
            "interval": [self.share.low, self.share.high],
        }


@dataclass(frozen=True)
class LeftOut:
    """The trials (and participants) the rates leave out, and why."""

    trials: int
    """Every step-3 trial of the export."""
    excluded_participants: Mapping[str, str]
    """Participant id -> why screening excluded them (those who never reached step 3 too)."""
    excluded_trials: int
    undecided_trials: int

    @property
    def analysed_trials(self) -> int:
        return self.trials - self.excluded_trials - self.undecided_trials

    def reasons(self) -> dict[str, int]:
        """Return how many excluded participants each exclusion reason has, most first (ties by name)."""
        counts = Counter(self.excluded_participants.values())
        return dict(sorted(counts.items(), key=lambda item: (-item[1], item[0])))

    def says(self) -> str:
        """Return, in words, how many trials were analysed and which were left out and why."""
        excluded = len(self.excluded_participants)
        left_out = []
        if excluded:
            reasons = ", ".join(f"{reason} {count}" for reason, count in self.reasons().items())
            left_out.append(
                f"{_count(self.excluded_trials, 'trial')} of {_count(excluded, 'participant')} excluded by "
                f"screening ({reasons})"
            )
        if self.undecided_trials:
            left_out.append(
                f"{_count(self.undecided_trials, 'undecided trial')} (the planner could not decide in time)"
            )
        said = f"{self.analysed_trials} of {_count(self.trials, 'trial')} analysed"
        return f"{said}; left out: {'; '.join(left_out)}." if left_out else f"{said}; none left out."


def _count(number: int, noun: str) -> str:
    return f"{number} {noun}{'' if number == 1 else 's'}"


@dataclass(frozen=True)
class RateTable:
    """One rate per condition and test object, and what the rates leave out."""

    rates: tuple[Rate, ...]
    left_out: LeftOut


def share(rows: Sequence[TrialRow]) -> Proportion:
    """Return the share of these trials that transferred, with its 95% Wilson interval (undecided count as 0)."""
    return wilson(sum(row.outcome or 0 for row in rows), len(rows))


def training_spans(rows: Sequence[TrialRow], catalog: Catalog) -> dict[str, str]:
    """Return, per condition, whether its training objects come from one category or from both."""
    categories: dict[str, set[str]] = {}
    for row in rows:
        categories.setdefault(row.condition, set()).update(catalog.get(o).category for o in row.training_objects)
    return {condition: span_of(found) for condition, found in categories.items()}


Cell = tuple[str, str | None, str, str | None]
"""A row of the table before counting: condition, training span, test object, near or far (None: unknown)."""


def _designed(study: Study, catalog: Catalog) -> list[Cell]:
    """Return the design's cells (condition, training span, test, near or far), in its order."""
    if study.design is None:
        return []
    cells = []
    for condition in study.design.conditions:
        try:  # the catalog may have lost an object the experiment used: its cells stay, unlabelled
            span: str | None = span_of(catalog.get(name).category for name in condition.training)
        except UnknownObjectError:
            span = None
        cells += [
            (condition.name, span, test, generalization_of(condition.training, test, catalog))
            for test in condition.tests
        ]
    return cells


def _tried(rows: Sequence[TrialRow], catalog: Catalog) -> list[Cell]:
    """Return the cells the trials name: conditions as they come, test objects sorted."""
    spans = training_spans(rows, catalog)
    cells: list[Cell] = []
    for condition, span in spans.items():
        mine = [row for row in rows if row.condition == condition]
        for test in sorted({row.test_object for row in mine}):
            cells.append((condition, span, test, next(r.generalization for r in mine if r.test_object == test)))
    return cells


def rate_table(study: Study, catalog: Catalog) -> RateTable:
    """Return the study's rates: the design's cells first (with or without trials), then any cell only trials name."""
    rows = study.rows
    cells = _designed(study, catalog)
    known = {(condition, test) for condition, _, test, _ in cells}
    cells += [cell for cell in _tried(rows, catalog) if (cell[0], cell[2]) not in known]
    rates = []
    for condition, span, test, near_or_far in cells:
        mine = [row for row in rows if row.condition == condition and row.test_object == test]
        included = [row for row in mine if not row.excluded]
        decided = [row for row in included if row.outcome is not None]
        undecided, excluded = len(included) - len(decided), len(mine) - len(included)
        rates.append(Rate(condition, span, test, near_or_far, share(decided), undecided, excluded))
    screened_out = {row.participant_id: row.exclusion_reason or "excluded" for row in rows if row.excluded}
    left_out = LeftOut(
        trials=len(rows),
        excluded_participants={**screened_out, **(study.exclusions or {})},
        excluded_trials=sum(1 for row in rows if row.excluded),
        undecided_trials=sum(1 for row in rows if not row.excluded and row.outcome is None),
    )
    return RateTable(tuple(rates), left_out)


def rates_figure(table: RateTable) -> Figure:
    """Return the chart of the rates: each condition's rate per test object, with its 95% Wilson interval.

    Test objects along x (every one of the table, with or without analysed trials); above each
    interval, transfers/analysed trials, centred on its point so neighbours never overlap; the
    legend beside the axes, never over the intervals.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    rates = table.rates
    tests = list(dict.fromkeys(rate.test_object for rate in rates))
    conditions = list(dict.fromkeys(rate.condition for rate in rates))
    figure = Figure(figsize=(max(5.0, 1.8 * len(tests) + 2.0), 3.8))
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    width = 0.6 / max(1, len(conditions))
    crowded = len(conditions) > 3  # then the counts stand upright, each above its own interval
    for index, condition in enumerate(conditions):
        shift = (index - (len(conditions) - 1) / 2) * width
        shown = [rate for rate in rates if rate.condition == condition and rate.rate is not None]
        xs = [tests.index(rate.test_object) + shift for rate in shown]
        percents = [100 * (rate.rate or 0.0) for rate in shown]
        # Wilson bounds can miss a rate of 0 or 1 by a rounding error; a bar is never negative.
        below = [max(0.0, 100 * ((rate.rate or 0.0) - (rate.share.low or 0.0))) for rate in shown]
        above = [max(0.0, 100 * ((rate.share.high or 0.0) - (rate.rate or 0.0))) for rate in shown]
        axes.errorbar(xs, percents, yerr=[below, above], fmt="o", capsize=4, label=condition)
        for x, percent, high, rate in zip(xs, percents, above, shown, strict=True):
            axes.annotate(
                f"{rate.transfers}/{rate.trials}",
                (x, percent + high),
                xytext=(0, 6),
                textcoords="offset points",
                ha="center",
                va="bottom",
                fontsize=7 if crowded else 8,
                rotation=90 if crowded else 0,
            )
    axes.set_xticks(range(len(tests)), [test.replace("_", " ") for test in tests])
    axes.set_xlim(-0.6, len(tests) - 0.4)
    axes.set_ylim(0, 125 if crowded else 115)  # room for the counts above an interval reaching 100%
    axes.set_yticks(range(0, 101, 20))
    axes.set_ylabel("models that transfer (%)")
    axes.set_title(
        "Transfer rate per condition and test object, with 95% Wilson intervals\n"
        f"(transfers/analysed trials; {table.left_out.says()})",
        fontsize=8,
    )
    axes.spines[["top", "right"]].set_visible(False)
    if conditions:
        axes.legend(
            title="condition", fontsize=8, title_fontsize=8, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1)
        )
    return figure


def rates_chart(table: RateTable, file_format: str = "svg") -> bytes:
    """Return the chart of the rates (``rates_figure``) as ``svg`` or ``png``."""
    from causalplan.causal.render import DRAW_LOCK

    with DRAW_LOCK:  # one lock for every matplotlib drawing in a process
        figure = rates_figure(table)
        buffer = io.BytesIO()
        figure.savefig(buffer, format=file_format, bbox_inches="tight", dpi=150 if file_format == "png" else None)
    return buffer.getvalue()
