"""The JSON answers of troubleshooting, one shape for the CLI (`--json`) and the HTTP service."""

from __future__ import annotations

from causalplan.troubleshoot.measures import REPAIR_BONUS
from causalplan.troubleshoot.task import TroubleshootingTask


def table_answer(task: TroubleshootingTask) -> dict[str, object]:
    """Return the strategies' table: `causalplan troubleshoot --all-faults --json`."""
    obj = task.obj
    return {
        "status": "solved",
        "object": obj.id,
        "fault_priors": obj.fault_priors,
        "repair_bonus": REPAIR_BONUS,
        "faults": {fault.part: fault.probability for fault in obj.faults},
        "strategies": {name: result.as_dict() for name, result in task.table().items()},
    }


def episode_answer(task: TroubleshootingTask, fault: str, strategy: str) -> dict[str, object]:
    """Return ``strategy``'s episode on the object broken at ``fault``, with every strategy's action count."""
    episode = task.episode(strategy, fault)
    return {
        "fault": fault,
        "strategy": strategy,
        "actions": episode.actions,
        "steps": [step.as_dict() for step in episode.steps],
        "strategies": {name: {"actions": task.episode(name, fault).actions} for name in task.strategies},
    }
