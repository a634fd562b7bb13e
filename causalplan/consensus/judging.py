"""Judging a crowd: every participant's transfer trials and the consensus model's, in one batch.

``run_batch`` solves equal planning problems once, so a consensus that equals most people's
model costs nothing extra. The report says who holds each consensus rule and what share.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from causalplan.consensus.build import Consensus
from causalplan.consensus.participants import Participant
from causalplan.objects.catalog import Catalog
from causalplan.transfer.batch import Trial, TrialResult, run_batch
from causalplan.transfer.verdict import Verdict

CONSENSUS_ID = "consensus"

TrialJudge = Callable[[list[Trial], Callable[[int], None] | None], list[TrialResult]]
"""Judges a list of trials and returns their results in order, calling the second argument with how many
trials were just judged (after each trial here, after each chunk on a cluster). ``local_judge`` makes
the one that runs here; the command line makes one that judges on a Dask cluster."""


def local_judge(catalog: Catalog, planner: str = "auto", time_limit: float = 30.0, simulate: bool = True) -> TrialJudge:
    """Return a trial judge that runs ``run_batch`` here, in this process."""

    def judge_here(trials: list[Trial], progress: Callable[[int], None] | None) -> list[TrialResult]:
        advance = None if progress is None else (lambda: progress(1))
        return run_batch(trials, catalog, planner, time_limit, simulate, advance)

    return judge_here


@dataclass(frozen=True)
class Judged:
    """A consensus with the verdicts of its members' trials and of its own, per test object."""

    consensus: Consensus
    individual: list[TrialResult]
    consensus_results: dict[str, TrialResult]

    def individual_rate(self, test_object: str | None = None) -> float | None:
        """Return the share of the members' trials (on one test object, or all) that transfer."""
        chosen = [r for r in self.individual if test_object is None or r.verdict.test_object == test_object]
        if not chosen:
            return None
        return sum(r.verdict.verdict is Verdict.TRANSFERS for r in chosen) / len(chosen)

    def consensus_transfers(self, test_object: str) -> bool:
        result = self.consensus_results.get(test_object)
        return result is not None and result.verdict.verdict is Verdict.TRANSFERS


def member_trials(consensus: Consensus, participants: list[Participant]) -> list[Trial]:
    """Return one trial per member and test object they mapped (the trial id is the member's)."""
    members = set(consensus.members)
    return [
        Trial(person.id, person.model, mapping, None)
        for person in participants
        if person.id in members
        for mapping in person.mappings.values()
    ]


def consensus_trials(consensus: Consensus) -> list[Trial]:
    """Return the consensus model's trial on each test object it has a mapping for."""
    return [
        Trial(f"{CONSENSUS_ID} on {test}", consensus.model_data, mapping.data, None)
        for test, mapping in consensus.mappings.items()
    ]


def judge(
    consensus: Consensus,
    participants: list[Participant],
    catalog: Catalog,
    planner: str = "auto",
    time_limit: float = 30.0,
    simulate: bool = True,
    progress: Callable[[int], None] | None = None,
    *,
    judge_trials: TrialJudge | None = None,
) -> Judged:
    """Return the verdicts of the members' trials and of the consensus on each test object.

    All of them are one batch, judged by ``judge_trials`` (which then decides the planner, time
    limit and simulation), or here by ``run_batch`` with ``planner``, ``time_limit`` and
    ``simulate``. ``progress`` is called with how many trials were just judged.
    """
    mine = member_trials(consensus, participants)
    own = consensus_trials(consensus)
    judging = judge_trials or local_judge(catalog, planner, time_limit, simulate)
    results = judging(mine + own, progress)
    tests = list(consensus.mappings)
    return Judged(consensus, results[: len(mine)], dict(zip(tests, results[len(mine) :], strict=True)))


def report(judged: Judged) -> dict[str, object]:
    """Return report.json: rules with support, label clusters, verdicts, rates, the consensus verdicts."""
    consensus = judged.consensus
    crowd = len(consensus.members)
    return {
        "training_object": consensus.training_object,
        "participants": crowd,
        "left_out": consensus.left_out,
        "min_support": consensus.min_support,
        "consensus_valid": consensus.loaded.is_valid,
        "consensus_problems": [d.message for d in consensus.loaded.report.errors],
        "rules": [
            {
                "rule": consensus.rule_text(rule),
                "entered": rule.entered,
                "support": rule.share,
                "holders": len(rule.holders),
                "participants": list(rule.holders),
                "left_out_because": rule.why_left_out,
            }
            for rule in consensus.rules
        ],
        "clusters": [node.as_dict() for node in consensus.nodes.values()],
        "mappings": {
            test: {
                "mappers": len(mapping.mappers),
                "consensus": mapping.data,
                "support": [
                    {
                        "part": part,
                        "function": consensus.nodes[node].label if node in consensus.nodes else node,
                        "share": round(len(people) / max(1, len(mapping.mappers)), 4),
                        "participants": list(people),
                    }
                    for (part, node), people in mapping.support.items()
                ],
            }
            for test, mapping in consensus.mappings.items()
        },
        "individual_verdicts": [
            {
                "id": result.trial_id,
                "test_object": result.verdict.test_object,
                "generalization": result.verdict.generalization,
                "verdict": result.verdict.verdict.value,
                "reasons": [reason.code for reason in result.verdict.reasons],
            }
            for result in judged.individual
        ],
        "individual_transfer_rate": judged.individual_rate(),
        "individual_transfer_rates": {test: judged.individual_rate(test) for test in consensus.mappings},
        "consensus_verdict": {
            test: {
                "verdict": result.verdict.verdict.value,
                "generalization": result.verdict.generalization,
                "reasons": [reason.as_dict() for reason in result.verdict.reasons],
                "plan": [step.text for step in result.verdict.plan.steps]
                if result.verdict.plan and result.verdict.plan.has_plan
                else None,
            }
            for test, result in judged.consensus_results.items()
        },
    }
