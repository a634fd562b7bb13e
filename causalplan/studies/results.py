"""An experiment's results: how many trials transferred, per condition and test object, and their bar chart."""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from causalplan.errors import UnknownObjectError
from causalplan.objects.catalog import Catalog
from causalplan.studies.design import Design, generalization


class TrialOutcome(Protocol):
    """What a rate counts of one stored step-3 trial: its condition, test object and verdict."""

    @property
    def condition(self) -> str: ...

    @property
    def test_object(self) -> str: ...

    @property
    def verdict(self) -> str: ...


@dataclass(frozen=True)
class Rate:
    """How often models transferred to one test object in one condition."""

    condition: str
    test_object: str
    generalization: str | None
    trials: int
    transfers: int
    fails: int
    undecided: int

    @property
    def rate(self) -> float | None:
        """Return the share of trials that transferred (None without trials)."""
        return self.transfers / self.trials if self.trials else None

    def as_dict(self) -> dict[str, Any]:
        return {**vars(self), "rate": self.rate}


def generalization_of(training: Sequence[str], test: str, catalog: Catalog) -> str | None:
    """Return ``near`` or ``far`` for a test object after these training objects (None: the catalog lost one)."""
    try:
        return generalization(training, test, catalog)
    except UnknownObjectError:  # the catalog no longer has an object the experiment used
        return None


def transfer_rates(design: Design, trials: Sequence[TrialOutcome], catalog: Catalog) -> list[Rate]:
    """Return one rate per condition and test object, in the design's order (rows without trials too)."""
    rates = []
    for condition in design.conditions:
        for test in condition.tests:
            verdicts = [
                trial.verdict for trial in trials if trial.condition == condition.name and trial.test_object == test
            ]
            rates.append(
                Rate(
                    condition.name,
                    test,
                    generalization_of(condition.training, test, catalog),
                    len(verdicts),
                    verdicts.count("transfers"),
                    verdicts.count("fails"),
                    len(verdicts) - verdicts.count("transfers") - verdicts.count("fails"),
                )
            )
    return rates


def chart_svg(rates: Sequence[Rate]) -> bytes:
    """Return a bar chart of the transfer rates as SVG: test objects along x, one bar per condition."""
    from matplotlib.backends.backend_svg import FigureCanvasSVG
    from matplotlib.figure import Figure

    tests = list(dict.fromkeys(rate.test_object for rate in rates))
    conditions = list(dict.fromkeys(rate.condition for rate in rates))
    figure = Figure(figsize=(max(5.0, 1.6 * len(tests) * max(1, len(conditions)) + 1.5), 3.6))
    FigureCanvasSVG(figure)
    axes = figure.add_subplot()
    width = 0.8 / max(1, len(conditions))
    for index, condition in enumerate(conditions):
        by_test = {rate.test_object: rate for rate in rates if rate.condition == condition}
        shift = (index - (len(conditions) - 1) / 2) * width
        present = [(position, by_test[test]) for position, test in enumerate(tests) if test in by_test]
        bars = axes.bar(
            [position + shift for position, _ in present],
            [100 * (rate.rate or 0.0) for _, rate in present],
            width * 0.92,
            label=condition,
        )
        for bar, (_, rate) in zip(bars, present, strict=True):
            axes.annotate(
                f"{rate.transfers}/{rate.trials}",
                (bar.get_x() + bar.get_width() / 2, bar.get_height()),
                ha="center",
                va="bottom",
                fontsize=8,
            )
    axes.set_xticks(range(len(tests)), [test.replace("_", " ") for test in tests])
    axes.set_ylim(0, 110)
    axes.set_ylabel("models that transfer (%)")
    axes.set_title("Transfer rate per condition and test object (transfers/trials above each bar)", fontsize=9)
    axes.spines[["top", "right"]].set_visible(False)
    if conditions:
        axes.legend(title="condition", fontsize=8, title_fontsize=8, frameon=False, loc="upper left")
    buffer = io.BytesIO()
    figure.savefig(buffer, format="svg", bbox_inches="tight")
    return buffer.getvalue()
