"""What a worker process runs to troubleshoot a broken object: the exact strategies' table, and the robot's episode.

``troubleshoot`` solves the model's, uniform's and the oracle's policies on the broken object
(``troubleshoot.task``), within a bound on the solver's states, and with a fault runs that
episode; with ``robot`` the Franka Panda then carries out the episode in physics, action by
action (``sim.robot_episode``), which takes seconds to minutes: that is a job's work, on the
jobs' pool, and its answer carries the 3D player's document of the run (``playback``, JSON
bytes). Typed arguments and the worker's catalog in, plain JSON values out, as ``planning``'s
functions.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from causalplan.causal.model import CausalModel, Labelling
from causalplan.objects.catalog import Catalog

if TYPE_CHECKING:
    from causalplan.objects.model import AssemblyObject
    from causalplan.sim.robot_episode_report import EpisodeInPhysics
    from causalplan.troubleshoot.episode import Episode

MAX_SERVICE_STATES = 500_000
"""The (belief, assembly) states one request may solve: the catalog's objects need at most a few thousand
(benchmarks/RESULTS.md). Beyond this it is refused (``troubleshooting_too_large``, 422)."""


@dataclass(frozen=True)
class TroubleshootingArguments:
    """A broken ``object_id`` (None: the mapping's, else the model's) troubleshot with ``model`` as the prior."""

    model: CausalModel
    mapping: Labelling | None
    object_id: str | None
    fault: str | None
    strategy: str
    robot: bool = False
    """With ``fault``: the Panda carries out the episode in physics (``robot`` in the answer)."""
    motors: bool = False
    """With ``robot``: its motor commands are also played through its joint motors (``robot.motors``)."""
    max_states: int = MAX_SERVICE_STATES


def troubleshoot(arguments: TroubleshootingArguments, catalog: Catalog) -> dict[str, Any]:
    """Return the strategies' table (as ``causalplan troubleshoot --all-faults --json``), the episode, the robot's run.

    Raises the troubleshooting errors (``unknown_fault_part``, ``fault_not_needed``, ...) and
    ``unknown_object`` as the CLI does.
    """
    from causalplan.troubleshoot.answer import episode_answer, table_answer
    from causalplan.troubleshoot.task import troubleshooting_task

    labelling = arguments.mapping
    chosen = arguments.object_id or (labelling or arguments.model.labelling).object_id
    task = troubleshooting_task(catalog.get(chosen), arguments.model, labelling, arguments.max_states)
    fault = arguments.fault
    answer: dict[str, Any] = {
        **table_answer(task),
        "episode": episode_answer(task, fault, arguments.strategy) if fault is not None else None,
    }
    if arguments.robot and fault is not None:
        from causalplan.sim.robot_episode import robot_episode

        episode = task.episode(arguments.strategy, fault)
        run = robot_episode(task.obj, episode, tracks=True, motors=arguments.motors)
        answer["robot"] = run.as_dict()
        answer["status"] = "repaired" if run.produces_goal else "not_repaired_in_physics"
        answer["playback"] = _playback(task.obj, run, episode)
    return answer


def _playback(obj: AssemblyObject, run: EpisodeInPhysics, episode: Episode) -> bytes | None:
    """Return the 3D player's document of the robot's run as JSON (None: the robot never moved).

    Encoded here, as ``robot.playback`` does: the job stores the bytes as they are.
    """
    from causalplan.sim.robot_episode_playback import episode_playback

    if run.commands is None or not run.commands.points or not run.tracks:
        return None  # it stopped at its first motion: there is nothing to play
    return json.dumps(episode_playback(obj, run, episode), separators=(",", ":")).encode()
