"""Answering a valid request: from the answer cache, or from a planner worker (then kept if final).

An answer's key is the canonical form of everything it depends on: the kind of answer, the
model, the mapping, the planner, the time limit and the catalog. So a repeated request, and
one that differs only in layout (whitespace, part, label and rule order), gets the kept answer.
"""

from __future__ import annotations

import hashlib
import json
import pickle
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from causalplan.caches import BoundedCache
from causalplan.causal.labels import display_label
from causalplan.causal.model import CausalModel, Labelling
from causalplan.limits import LimitExceededError
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import catalog_task
from causalplan.pddl.writer import compile_task
from causalplan.planners import pipeline
from causalplan.planners.result import PlanStatus
from causalplan.service.pool import jobs
from causalplan.service.pool.pool import PlannerPool
from causalplan.settings import Settings
from causalplan.transfer.verdict import Verdict

DEFAULT_PLANNER = "auto"
FALLBACK_PLANNER = "fd"
SIMULATION_SECONDS = 30.0
"""Time a worker gets for the simulation and its picture, beyond the planner's limit."""
MAX_ANSWER_BYTES = 256 * 1024
"""Answers larger than this (pickled) are not kept, so a full cache holds at most ``size`` times it."""


class ResultCache:
    """Planners' answers by key, kept pickled (each ``get`` returns a fresh copy); safe to share between threads."""

    def __init__(self, size: int) -> None:
        self._pickles: BoundedCache[str, bytes] = BoundedCache(size)

    def get(self, key: str) -> dict[str, Any] | None:
        """Return a copy of the answer kept for ``key``, or None."""
        data = self._pickles.get(key)
        if data is None:
            return None
        answer: dict[str, Any] = pickle.loads(data)  # our own bytes, never a client's
        return answer

    def put(self, key: str, value: dict[str, Any]) -> None:
        """Keep a copy of ``value`` for ``key`` (not when the cache is off or the answer is too large)."""
        data = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
        if len(data) <= MAX_ANSWER_BYTES:
            self._pickles.put(key, data)

    def clear(self) -> None:
        """Forget every kept answer."""
        self._pickles.clear()

    def __len__(self) -> int:
        return len(self._pickles)

    def stats(self) -> dict[str, int]:
        """Return the size, entries, hits and misses."""
        return self._pickles.stats()


def catalog_key(catalog: Catalog) -> str:
    """Return a fingerprint of the catalog's objects (computed once, when the service starts)."""
    text = repr(sorted(catalog.objects.items()))
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


def canonical_labelling(labelling: Labelling) -> dict[str, object]:
    """Return a labelling in a canonical form: parts sorted, each part's labels sorted."""
    return {
        "object": labelling.object_id,
        "functions": {
            part: sorted({display_label(label) for label in labels})
            for part, labels in sorted(labelling.functions.items())
            if labels
        },
    }


def canonical_model(model: CausalModel) -> dict[str, object]:
    """Return a model in a canonical form: whitespace, part, label and rule order do not matter.

    Case is kept, because answers quote the labels as written.
    """
    rules = sorted(
        " AND ".join(sorted({display_label(cause) for cause in rule.causes})) + " CAUSES " + display_label(rule.effect)
        for rule in model.rules
    )
    return {**canonical_labelling(model.labelling), "goal": display_label(model.goal), "rules": rules}


def canonical_text(value: dict[str, object] | None) -> str:
    """Return the canonical JSON text of a canonical form (keys sorted, text as written)."""
    return json.dumps(value, sort_keys=True, ensure_ascii=False)


def model_text(model: CausalModel) -> str:
    """Return the model's canonical text: equal for models that differ only in layout."""
    return canonical_text(canonical_model(model))


def mapping_text(mapping: Labelling | None) -> str:
    """Return the canonical text of a step-3 mapping (of no mapping too)."""
    return canonical_text(canonical_labelling(mapping) if mapping is not None else None)


def model_hash(model: CausalModel) -> str:
    """Return the stored hash of the model's canonical form (equal for models that differ only in layout)."""
    return hashlib.sha256(model_text(model).encode("utf-8", "replace")).hexdigest()


def answer_key(kind: str, model: str, mapping: str, planner: str, time_limit: float, catalog: str) -> str:
    """Return the cache key of an answer from the canonical texts of its model and mapping.

    A time limit is in it because it can change which planner answers.
    """
    text = json.dumps([kind, model, mapping, planner, float(time_limit), catalog], ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


def resolve_planner(requested: str) -> str:
    """Return the registry name to run for ``requested``; UnknownPlannerError when there is none.

    The registry is read at request time, so planners registered later are accepted as they come.
    """
    names = pipeline.PLANNERS
    if requested == DEFAULT_PLANNER and DEFAULT_PLANNER not in names:
        return FALLBACK_PLANNER  # a registry without 'auto' still gets a working default
    if requested not in names:
        choices = list(dict.fromkeys([DEFAULT_PLANNER, *names]))
        raise pipeline.UnknownPlannerError(
            f"Unknown planner '{requested}'; choose one of: {', '.join(choices)}.",
            details={"planner": requested, "planners": choices},
        )
    return requested


def default_planner() -> str:
    """Return what the default planner ('auto') runs as, right now."""
    return resolve_planner(DEFAULT_PLANNER)


def resolve_time_limit(requested: float | None, settings: Settings) -> float:
    """Return the solve's time limit; LimitExceededError when it is over the server's maximum."""
    if requested is None:
        return settings.default_time_limit
    if requested > settings.max_time_limit:
        raise LimitExceededError(
            "time_limit_too_long",
            f"time_limit {requested:g} s is over this server's maximum of {settings.max_time_limit:g} s.",
            details={"limit": settings.max_time_limit, "actual": requested, "field": "time_limit"},
        )
    return requested


@dataclass(frozen=True)
class Answer:
    """A planner's answer (a JSON-ready dict), whether it came from the cache, and how long it took."""

    data: dict[str, Any]
    cached: bool
    seconds: float


@dataclass(frozen=True)
class Answerer:
    """What answering needs: the cache, the pool, the settings and the catalog's fingerprint."""

    cache: ResultCache
    pool: PlannerPool
    settings: Settings
    catalog_key: str

    def key(self, kind: str, model: CausalModel, mapping: Labelling | None, planner: str, limit: float) -> str:
        """Return the key of an answer of ``kind`` ('plan', 'transfer', 'simulate:True', ...)."""
        return answer_key(kind, model_text(model), mapping_text(mapping), planner, limit, self.catalog_key)

    def _answer(
        self,
        key: str,
        job: Callable[..., dict[str, Any]],
        args: tuple[Any, ...],
        seconds: float,
        is_final: Callable[[dict[str, Any]], bool],
        meanwhile: Callable[[], None] | None,
    ) -> Answer:
        """Return the answer kept for ``key``, or ``job(*args)`` from a worker (kept when ``is_final``).

        Blocks while no worker is free: call it in a thread. ``meanwhile`` (e.g. storing the
        request's record) runs while the worker works, or first for a kept answer; not for a
        request refused before a worker took it.
        """
        started = time.perf_counter()
        cached = self.cache.get(key)
        if cached is not None:
            if meanwhile is not None:
                meanwhile()
            return Answer(cached, True, time.perf_counter() - started)
        data = self.pool.run(job, args, seconds, meanwhile)
        if is_final(data):  # a timeout may go otherwise next time
            self.cache.put(key, data)
        return Answer(data, False, time.perf_counter() - started)

    def _args(self, model: CausalModel, mapping: Labelling | None, planner: str, limit: float) -> tuple[Any, ...]:
        return (model, mapping, planner, limit, tuple(self.settings.catalog_folders))

    def plan(
        self,
        model: CausalModel,
        mapping: Labelling | None,
        planner: str,
        time_limit: float,
        meanwhile: Callable[[], None] | None = None,
        val: bool = False,
    ) -> Answer:
        """Return the plan of ``model`` (on ``mapping``'s object), as ``plan --json``; ``val``: VAL checks it too."""
        key = self.key("plan:val" if val else "plan", model, mapping, planner, time_limit)
        seconds = time_limit + self.settings.solve_grace_seconds
        args = (*self._args(model, mapping, planner, time_limit), val)
        return self._answer(key, jobs.plan_job, args, seconds, _is_final_plan, meanwhile)

    def transfer(
        self,
        model: CausalModel,
        mapping: Labelling,
        planner: str,
        time_limit: float,
        val: bool = False,
        robot: bool = False,
    ) -> Answer:
        """Return the transfer verdict of ``model`` through ``mapping``, as ``causalplan transfer --json``.

        ``robot``: the robot has the last word (a plan it cannot carry out fails, ``robot_cannot_execute``).
        """
        kind = "transfer" + (":val" if val else "") + (":robot" if robot else "")
        key = self.key(kind, model, mapping, planner, time_limit)
        seconds = time_limit + self.settings.solve_grace_seconds + (self.settings.robot_seconds if robot else 0.0)
        args = (*self._args(model, mapping, planner, time_limit), val, robot)
        return self._answer(key, jobs.transfer_job, args, seconds, _is_final_verdict, None)

    def simulate(
        self,
        model: CausalModel,
        mapping: Labelling | None,
        planner: str,
        time_limit: float,
        picture: bool,
        meanwhile: Callable[[], None] | None = None,
        val: bool = False,
    ) -> Answer:
        """Return the plan and its simulation report (and picture); ``val``: VAL checks the plan too."""
        key = self.key(f"simulate:{picture}" + (":val" if val else ""), model, mapping, planner, time_limit)
        seconds = time_limit + self.settings.solve_grace_seconds + SIMULATION_SECONDS
        args = (*self._args(model, mapping, planner, time_limit), picture, False, val)
        return self._answer(key, jobs.simulate_job, args, seconds, _is_final_simulation, meanwhile)


def _is_final_plan(data: dict[str, Any]) -> bool:
    return PlanStatus(str(data["status"])).is_final()


def _is_final_verdict(data: dict[str, Any]) -> bool:
    return bool(data["verdict"] != Verdict.UNDECIDED.value)


def _is_final_simulation(data: dict[str, Any]) -> bool:
    return isinstance(data["planning"], dict) and _is_final_plan(data["planning"])


def compiled_pddl(catalog: Catalog, model: CausalModel, mapping: Labelling | None) -> dict[str, str]:
    """Return the readable PDDL domain and problem of a plan request (pure and quick: done here, not by a worker)."""
    compiled = compile_task(catalog_task(model, catalog, mapping))
    return {"domain": compiled.domain, "problem": compiled.problem}
