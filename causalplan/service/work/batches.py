"""What a worker process runs for long work: judge a chunk of trials, build a consensus, estimate a fit.

Jobs (``service.jobs``) split their work into these calls, each run on the jobs' own pool, so
progress moves a call at a time and a cancel stops the worker. Functions take typed arguments
and the worker's catalog, as ``planning``'s do.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from causalplan.objects.catalog import Catalog
from causalplan.transfer.batch import Trial, TrialResult, run_batch


@dataclass(frozen=True)
class TrialsArguments:
    """A chunk of a batch's trials, judged as ``causalplan batch`` judges them; ``val``: VAL checks each plan."""

    trials: tuple[Trial, ...]
    planner: str
    time_limit: float
    simulate: bool
    val: bool = False


@dataclass(frozen=True)
class ConsensusArguments:
    """The participants of an upload (JSON Lines ``text``, ``count`` of them), for ``causalplan consensus``."""

    text: str
    count: int
    min_support: float
    planner: str
    time_limit: float
    simulate: bool


@dataclass(frozen=True)
class FitEstimateArguments:
    """One fit's success probability, estimated by ``trials`` noisy insertions (``causalplan estimate-fits``)."""

    object_id: str
    fit_id: str
    trials: int
    seed: int
    noise_mm: float
    noise_deg: float


def judged_trials(arguments: TrialsArguments, catalog: Catalog) -> list[TrialResult]:
    """Return the results of a chunk of trials."""
    return run_batch(
        list(arguments.trials), catalog, arguments.planner, arguments.time_limit, arguments.simulate, val=arguments.val
    )


def consensus_report(arguments: ConsensusArguments, catalog: Catalog) -> dict[str, Any]:
    """Return ``causalplan consensus``'s report.json of the participants in the upload."""
    from causalplan.consensus.build import build_consensus
    from causalplan.consensus.judging import judge, report
    from causalplan.consensus.participants import read_participants

    with tempfile.TemporaryDirectory(prefix="causalplan-upload-") as folder:
        path = Path(folder) / "crowd.jsonl"
        path.write_text(arguments.text, encoding="utf-8", errors="surrogatepass")
        participants = read_participants(path)
    crowd = build_consensus(participants, catalog, arguments.min_support)
    return report(judge(crowd, participants, catalog, arguments.planner, arguments.time_limit, arguments.simulate))


def fit_estimate(arguments: FitEstimateArguments, catalog: Catalog) -> dict[str, object]:
    """Return ``FitEstimate.as_dict()`` of one fit of the object."""
    from causalplan.sim.fit_estimates import estimate_fits

    obj = catalog.get(arguments.object_id)
    (estimate,) = estimate_fits(
        obj, arguments.trials, arguments.seed, arguments.noise_mm, arguments.noise_deg, (arguments.fit_id,)
    )
    return estimate.as_dict()
