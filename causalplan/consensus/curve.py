"""The crowd curve: does the consensus of n people transfer more often than the average person?

For each draw a fresh synthetic population is made (seed + draw), every member's trials are
judged once, and the consensus of its first n members is built and judged, for each crowd
size n. Per size and test object it reports the consensus's transfer rate over the draws
(with a Wilson 95% interval) and the mean individual's rate (the crowd's own members, with the
2.5-97.5 percentiles over draws).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from causalplan.consensus.build import MIN_SUPPORT, build_consensus
from causalplan.consensus.judging import consensus_trials
from causalplan.consensus.participants import Participant
from causalplan.consensus.population import population, scenario_for
from causalplan.objects.catalog import Catalog
from causalplan.studies.statistics import wilson
from causalplan.transfer.batch import Trial, run_batch
from causalplan.transfer.verdict import Verdict

CROWD_SIZES = (1, 3, 10, 30, 100)


@dataclass(frozen=True)
class CurvePoint:
    """One crowd size on one test object: the consensus's and the mean individual's transfer rates."""

    size: int
    test_object: str
    generalization: str
    draws: int
    consensus_rate: float
    consensus_low: float
    consensus_high: float
    individual_rate: float
    individual_low: float
    individual_high: float

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


def _participants(lines: list[dict[str, object]]) -> list[Participant]:
    people: dict[str, Participant] = {}
    for line in lines:
        person = people.setdefault(str(line["id"]), Participant(str(line["id"]), line["model"], where=str(line["id"])))
        mapping = line["mapping"]
        assert isinstance(mapping, dict)
        person.mappings[str(mapping["object"])] = mapping
    return list(people.values())


def _wilson(successes: int, total: int) -> tuple[float, float]:
    share = wilson(successes, total)
    assert share.low is not None and share.high is not None, "a curve point always has draws"
    return share.low, share.high


def crowd_curve(
    training: str,
    catalog: Catalog,
    sizes: Sequence[int] = CROWD_SIZES,
    draws: int = 10,
    seed: int = 0,
    rates: dict[str, float] | None = None,
    tests: tuple[str, ...] = (),
    min_support: float = MIN_SUPPORT,
    planner: str = "auto",
    time_limit: float = 30.0,
    simulate: bool = True,
    progress: Callable[[], None] | None = None,
) -> list[CurvePoint]:
    """Return one point per crowd size and test object, over ``draws`` independent populations."""
    chosen = tests or tuple(scenario_for(training).test_parts)
    largest = max(sizes)
    consensus_hits: dict[tuple[int, str], list[bool]] = {}
    individual_means: dict[tuple[int, str], list[float]] = {}
    for draw in range(draws):
        people = _participants(population(training, largest, seed + draw, rates, chosen))
        trials = [Trial(p.id, p.model, p.mappings[test], None) for p in people for test in chosen]
        results = run_batch(trials, catalog, planner, time_limit, simulate)
        transfers = {
            (result.trial_id, test): result.verdict.verdict is Verdict.TRANSFERS
            for result, (_, test) in zip(results, [(p.id, t) for p in people for t in chosen], strict=True)
        }
        for size in sizes:
            crowd = people[:size]
            consensus = build_consensus(crowd, catalog, min_support)
            own = consensus_trials(consensus)
            verdicts = dict(
                zip(consensus.mappings, run_batch(own, catalog, planner, time_limit, simulate), strict=True)
            )
            for test in chosen:
                result = verdicts.get(test)
                hit = result is not None and result.verdict.verdict is Verdict.TRANSFERS and consensus.loaded.is_valid
                consensus_hits.setdefault((size, test), []).append(hit)
                individual_means.setdefault((size, test), []).append(
                    float(np.mean([transfers[(person.id, test)] for person in crowd]))
                )
            if progress is not None:
                progress()
    points = []
    for test in chosen:
        kind = "near" if catalog.get(test).category == catalog.get(training).category else "far"
        for size in sizes:
            hits, means = consensus_hits[(size, test)], individual_means[(size, test)]
            low, high = _wilson(sum(hits), len(hits))
            points.append(
                CurvePoint(
                    size,
                    test,
                    kind,
                    len(hits),
                    sum(hits) / len(hits),
                    low,
                    high,
                    float(np.mean(means)),
                    float(np.percentile(means, 2.5)),
                    float(np.percentile(means, 97.5)),
                )
            )
    return points


def plot_curve(points: list[CurvePoint], path: Path, title: str) -> None:
    """Draw consensus vs mean individual transfer rate against crowd size, one panel per test object."""
    from matplotlib.figure import Figure

    from causalplan.causal.render import DRAW_LOCK

    tests = list(dict.fromkeys(point.test_object for point in points))
    figure = Figure(figsize=(4.2 * len(tests), 3.8))
    for number, test in enumerate(tests):
        axes = figure.add_subplot(1, len(tests), number + 1)
        mine = [point for point in points if point.test_object == test]
        sizes = [point.size for point in mine]
        axes.plot(sizes, [p.consensus_rate for p in mine], "o-", color="#1f77b4", label="consensus model")
        axes.fill_between(
            sizes, [p.consensus_low for p in mine], [p.consensus_high for p in mine], color="#1f77b4", alpha=0.2
        )
        axes.plot(sizes, [p.individual_rate for p in mine], "s--", color="#d62728", label="mean individual")
        axes.fill_between(
            sizes, [p.individual_low for p in mine], [p.individual_high for p in mine], color="#d62728", alpha=0.15
        )
        axes.set_xscale("log")
        axes.set_xticks(sizes, [str(size) for size in sizes])
        axes.set_ylim(-0.03, 1.03)
        axes.set_xlabel("crowd size")
        axes.set_title(f"{test.replace('_', ' ')} ({mine[0].generalization})", fontsize=10)
        if number == 0:
            axes.set_ylabel("transfer rate")
            axes.legend(loc="lower right", fontsize=8)
        axes.grid(alpha=0.3)
    figure.suptitle(title, fontsize=10)
    with DRAW_LOCK:
        figure.savefig(path, bbox_inches="tight", dpi=120)
