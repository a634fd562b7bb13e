"""The troubleshooting job the service sends its planner workers: the strategies' table, and an episode.

Like ``pool.jobs``: runs inside a worker process (a large user object cannot hold up the
service, and the pool kills it at its time limit), plain values in, a JSON-ready dict out.
"""

from __future__ import annotations

from pathlib import Path

from causalplan.causal.model import CausalModel, Labelling
from causalplan.service.pool.catalog import worker_catalog
from causalplan.troubleshoot.measures import REPAIR_BONUS
from causalplan.troubleshoot.task import troubleshooting_task


def troubleshooting_job(
    model: CausalModel,
    mapping: Labelling | None,
    object_id: str | None,
    fault: str | None,
    strategy: str,
    catalog_folders: tuple[Path, ...],
    max_states: int,
) -> dict[str, object]:
    """Return `causalplan troubleshoot --all-faults --json`, with ``episode`` (as ``--fault --json``) for a fault."""
    catalog = worker_catalog(catalog_folders)
    chosen = object_id or (mapping or model.labelling).object_id
    task = troubleshooting_task(catalog.get(chosen), model, mapping, max_states)
    episode = None
    if fault is not None:
        run = task.episode(strategy, fault)
        episode = {
            "fault": fault,
            "strategy": strategy,
            "actions": run.actions,
            "steps": [step.as_dict() for step in run.steps],
            "strategies": {name: {"actions": task.episode(name, fault).actions} for name in task.strategies},
        }
    obj = task.obj
    return {
        "status": "solved",
        "object": obj.id,
        "fault_priors": obj.fault_priors,
        "repair_bonus": REPAIR_BONUS,
        "faults": {item.part: item.probability for item in obj.faults},
        "strategies": {name: result.as_dict() for name, result in task.table().items()},
        "episode": episode,
    }
