"""The crowd curve: does the consensus of n people transfer more often than the average person?

For each draw a fresh synthetic population is made (seed + draw), every member's trials are
judged once, and the consensus of its first n members is built and judged, for each crowd
size n. Per size and test object it reports the consensus's transfer rate over the draws
(with a Wilson 95% interval) and the mean individual's rate (the crowd's own members, with the
2.5-97.5 percentiles over draws). All the draws' trials are judged as one batch, so a cluster
gets chunks of every draw at once.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from causalplan.consensus.build import MIN_SUPPORT, build_consensus
from causalplan.consensus.judging import TrialJudge, consensus_trials, local_judge
from causalplan.consensus.participants import Participant
from causalplan.consensus.population import population, scenario_for
from causalplan.objects.catalog import Catalog
from causalplan.studies.statistics import wilson
from causalplan.transfer.batch import Trial
from causalplan.transfer.generalization import near_or_far
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


@dataclass(frozen=True)
class _Crowd:
    """One draw's crowd of one size: what its consensus has mappings for, and whether its model is valid."""

    size: int
    members: list[str]
    mapped: list[str]
    is_valid: bool


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
    progress: Callable[[int, int], None] | None = None,
    *,
    judge_trials: TrialJudge | None = None,
) -> list[CurvePoint]:
    """Return one point per crowd size and test object, over ``draws`` independent populations.

    Every draw's populations and consensuses are made first, then all their trials are judged
    as one batch, by ``judge_trials`` (which then decides the planner, time limit and
    simulation; e.g. on a Dask cluster) or here by ``run_batch``. ``progress`` is called with
    (trials judged, trials in all) as the batch goes.
    """
    chosen = tests or tuple(scenario_for(training).test_parts)
    largest = max(sizes)
    trials: list[Trial] = []
    made: list[tuple[list[Participant], list[_Crowd]]] = []
    for draw in range(draws):
        people = _participants(population(training, largest, seed + draw, rates, chosen))
        trials += [Trial(p.id, p.model, p.mappings[test], None) for p in people for test in chosen]
        crowds = []
        for size in sizes:
            consensus = build_consensus(people[:size], catalog, min_support)
            trials += consensus_trials(consensus)
            members = [person.id for person in people[:size]]
            crowds.append(_Crowd(size, members, list(consensus.mappings), consensus.loaded.is_valid))
        made.append((people, crowds))
    judged = 0

    def advance(count: int) -> None:
        nonlocal judged
        judged += count
        if progress is not None:
            progress(judged, len(trials))

    if progress is not None:
        progress(0, len(trials))
    judging = judge_trials or local_judge(catalog, planner, time_limit, simulate)
    results = iter(judging(trials, advance))
    consensus_hits: dict[tuple[int, str], list[bool]] = {}
    individual_means: dict[tuple[int, str], list[float]] = {}
    for people, crowds in made:
        transfers: dict[tuple[str, str], bool] = {}
        for person in people:  # the results come in the order the trials were made
            for test in chosen:
                transfers[(person.id, test)] = next(results).verdict.verdict is Verdict.TRANSFERS
        for crowd in crowds:
            verdicts = {test: next(results) for test in crowd.mapped}
            for test in chosen:
                result = verdicts.get(test)
                hit = result is not None and result.verdict.verdict is Verdict.TRANSFERS and crowd.is_valid
                consensus_hits.setdefault((crowd.size, test), []).append(hit)
                individual_means.setdefault((crowd.size, test), []).append(
                    float(np.mean([transfers[(member, test)] for member in crowd.members]))
                )
    points = []
    for test in chosen:
        kind = near_or_far([catalog.get(training).category], catalog.get(test).category)
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
