"""Whether this replica is ready for participants: its planner pool has answered a plan of its own.

``/health`` answers as soon as the app is up (liveness), but the pool's workers are still
warming then (the translator imported, the first search started), and a first plan could take
seconds. So at start one plan of a catalog object (every part needed: the largest task the
object makes) goes through the pool, like a request, bypassing the answer cache; once a worker
has answered it, ``GET /health/ready`` says 200. A load balancer, compose's health check, or a
test sends participants only then.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field

from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel, read_model
from causalplan.errors import CausalPlanError
from causalplan.objects.catalog import Catalog
from causalplan.service.work.calls import Workers
from causalplan.service.work.planning import PlanArguments
from causalplan.service.work.registry import PLAN

logger = logging.getLogger(__name__)

PREFERRED_OBJECT = "desk_lamp"
"""The object of the readiness plan when the catalog has it (the paper's first training object)."""
TRIES = 3
"""Plans tried before the replica gives up being ready (each failure is logged)."""
STARTING = "the planner pool has not answered its first plan yet"


@dataclass
class Readiness:
    """Whether the readiness plan has been answered, and why not while it has not."""

    ready: threading.Event = field(default_factory=threading.Event)
    problem: str | None = STARTING

    def is_ready(self) -> bool:
        return self.ready.is_set()


def readiness_model(catalog: Catalog) -> CausalModel:
    """Return a model of the preferred object (else the first) whose one rule needs every part."""
    obj = catalog.objects.get(PREFERRED_OBJECT) or catalog.objects[sorted(catalog.objects)[0]]
    functions = {part: [f"what the {part} does"] for part in obj.part_ids}
    rule = " AND ".join(labels[0] for labels in functions.values()) + f" CAUSES {obj.goal}"
    document = {"object": obj.id, "goal": obj.goal, "functions": functions, "rules": [rule]}
    model, _ = read_model(document, SourceMap("readiness"))
    assert model is not None, "a model built from the catalog's own parts always reads"
    return model


def prove_ready(work: Workers, catalog: Catalog, planner: str, readiness: Readiness) -> None:
    """Plan the readiness model on an interactive worker (up to ``TRIES`` times); set ``readiness`` once one answers."""
    arguments = PlanArguments(readiness_model(catalog), None, planner, work.settings.default_time_limit)
    for attempt in range(1, TRIES + 1):
        try:
            work.run(PLAN, arguments)  # not ``answer``: a kept answer would prove no worker
        except CausalPlanError as exc:
            readiness.problem = f"the readiness plan failed ({exc.code}): {exc.message}"
            logger.warning("readiness plan %d of %d failed: %s", attempt, TRIES, exc.message)
            continue
        readiness.problem = None
        readiness.ready.set()
        logger.info("ready: the planner pool answered its first plan")
        return


def start_proving(work: Workers, catalog: Catalog, planner: str) -> Readiness:
    """Return a new ``Readiness`` and start the thread that proves it with a plan by ``planner``."""
    readiness = Readiness()
    threading.Thread(
        target=prove_ready, args=(work, catalog, planner, readiness), name="causalplan-readiness", daemon=True
    ).start()
    return readiness
