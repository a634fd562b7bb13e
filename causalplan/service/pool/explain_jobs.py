"""The jobs of explanations the service sends its planner workers: explain a plan, search repairs.

Like ``pool.jobs``: run inside a worker process, plain values in, JSON-ready dicts out.
"""

from __future__ import annotations

import time
from pathlib import Path

from causalplan.causal.model import CausalModel, Labelling
from causalplan.explain.explanation import explain_plan
from causalplan.explain.repair import search_repairs
from causalplan.pddl.task import catalog_task
from causalplan.service.pool.catalog import worker_catalog
from causalplan.transfer.verdict import Verdict, evaluate_transfer

PLANS_PER_EXPLANATION = 2
"""An explanation plans at most twice (the plan, and a why-not's alternative): its time limit is twice a plan's."""


def explanation_job(
    model: CausalModel,
    mapping: Labelling | None,
    planner: str,
    time_limit: float,
    catalog_folders: tuple[Path, ...],
    why: str | None,
    why_not: str | None,
    val: bool,
    simulate: bool,
) -> dict[str, object]:
    """Return ``causalplan explain --json`` for the plan of ``model`` (on the mapping's object if given)."""
    task = catalog_task(model, worker_catalog(catalog_folders), mapping)
    return explain_plan(task, why, why_not, planner, time_limit, val, simulate).as_dict()


def repair_job(
    model: CausalModel,
    mapping: Labelling,
    planner: str,
    time_limit: float,
    catalog_folders: tuple[Path, ...],
    val: bool,
    seconds: float,
) -> dict[str, object] | None:
    """Return the repairs of a failed transfer (``RepairSearch.as_dict()``), or None when it does not fail.

    ``seconds``: the whole job's budget, whatever ``time_limit`` is; the search stops there with what it found.
    """
    deadline = time.monotonic() + seconds
    catalog = worker_catalog(catalog_folders)
    verdict = evaluate_transfer(model, mapping, catalog, planner, min(time_limit, seconds), val=val)
    if verdict.verdict is not Verdict.FAILS:
        return None
    left = max(0.0, deadline - time.monotonic())
    search = search_repairs(
        model, mapping, catalog, verdict, planner=planner, time_limit=time_limit, val=val, seconds=left
    )
    return search.as_dict()
