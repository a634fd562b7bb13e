"""Plans drawn before anyone asks: the pictures of the plans participants' models are likely to get.

A participant waits for the picture after "Show the robot's plan", and drawing one runs the
simulator. The plan of a model on an object depends only on which parts the model needs, so
drawing the plan of each set of an object's parts (largest first: most models use most parts)
covers most models before a participant writes them. Each plan also lands in the answer cache.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from itertools import combinations, islice

from causalplan.causal.documents import SourceMap
from causalplan.causal.model import CausalModel, read_model
from causalplan.errors import CausalPlanError
from causalplan.objects.model import AssemblyObject
from causalplan.service.deps import Services
from causalplan.service.documents import default_planner
from causalplan.service.pages.drawings import plan_picture
from causalplan.service.work.planning import PlanArguments
from causalplan.service.work.registry import PLAN

logger = logging.getLogger(__name__)

MAX_PART_SETS = 32
"""Part sets drawn per object at most (an object of 5 parts has 31); larger objects get their largest sets."""


def part_sets(obj: AssemblyObject) -> Iterator[tuple[str, ...]]:
    """Return the object's sets of two or more parts (one part needs no step), largest first, MAX_PART_SETS at most."""
    largest_first = (parts for size in range(len(obj.part_ids), 1, -1) for parts in combinations(obj.part_ids, size))
    return islice(largest_first, MAX_PART_SETS)


def needing(obj: AssemblyObject, parts: tuple[str, ...]) -> CausalModel:
    """Return a model of ``obj`` whose one rule needs exactly ``parts`` (each carries one function)."""
    functions = {part: [f"what the {part} does"] for part in parts}
    rule = " AND ".join(label for labels in functions.values() for label in labels) + f" CAUSES {obj.goal}"
    model, _ = read_model(
        {"object": obj.id, "goal": obj.goal, "functions": functions, "rules": [rule]}, SourceMap("ahead")
    )
    assert model is not None, "a model built from plain data always reads"
    return model


def plan_fits(services: Services, model: CausalModel) -> tuple[str, ...]:
    """Return the fits of the robot's plan of ``model``, in order (empty when there is no plan)."""
    arguments = PlanArguments(model, None, default_planner(), services.settings.default_time_limit)
    answer = services.work.answer(PLAN, arguments)
    steps = answer.data.get("plan") or []
    fits = tuple(str(step.get("fit") or "") for step in steps)
    return fits if fits and all(fits) else ()


def draw_ahead(services: Services, objects: list[AssemblyObject], stop: threading.Event) -> int:
    """Draw the picture of the plan of each part set of each object until done or ``stop``; return how many."""
    drawn = 0
    for obj in objects:
        for parts in part_sets(obj):
            if stop.is_set():
                return drawn
            try:
                fits = plan_fits(services, needing(obj, parts))
                if fits:
                    plan_picture(services, obj, fits)
                    drawn += 1
            except CausalPlanError as exc:  # busy, closing, no simulator: the request will draw it
                logger.info("not drawn ahead: %s %s: %s", obj.id, ",".join(parts), exc.message)
                if stop.is_set():
                    return drawn
    return drawn
