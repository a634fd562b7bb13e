"""The one way to run work in a worker process: ``Workers``, kept answers and all.

``Workers.run`` runs a registered ``Work`` on the pool it names, with the time limit it
declares and the catalog's folders added; every call of the interactive pool passes through
``Workers.interactive_call``, and of the jobs' pool through ``Workers.queued_call``.
``Workers.answer`` first looks in the answer cache, whose key is the work's name, what its
arguments depend on (``canonical_key``: the canonical texts of the model and the mapping, the
planner, the time limit, ...) and the catalog's fingerprint; a final answer is kept.
"""

from __future__ import annotations

import hashlib
import json
import pickle
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, fields
from typing import Any, TypeVar

from causalplan.caches import BoundedCache
from causalplan.causal.canonical import mapping_text, model_text
from causalplan.objects.catalog import Catalog
from causalplan.service.errors import QueueFullError
from causalplan.service.pool.pool import PlannerPool, RunStoppedError
from causalplan.service.pool.turns import background
from causalplan.service.work.planning import ProbeArguments
from causalplan.service.work.registry import PROBE, Pool, Work, perform
from causalplan.settings import Settings

A = TypeVar("A")
R = TypeVar("R")

MAX_ANSWER_BYTES = 256 * 1024
"""Answers larger than this (pickled) are not kept, so a full cache holds at most ``size`` times it."""


class WorkStoppedError(Exception):
    """The caller's ``stop`` event was set while its worker worked: the worker was killed (and replaced)."""


class ResultCache:
    """Answers by key, kept pickled (each ``get`` returns a fresh copy); safe to share between threads."""

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


def canonical_key(arguments: object) -> str:
    """Return what an answer to ``arguments`` (a dataclass) depends on, layout aside.

    The model and the mapping count by their canonical texts, the time limit as a number.
    """
    values: list[object] = []
    for field in fields(arguments):  # type: ignore[arg-type]  # the registry's arguments are dataclasses
        value = getattr(arguments, field.name)
        if field.name == "model":
            value = model_text(value)
        elif field.name == "mapping":
            value = mapping_text(value)
        elif field.name == "time_limit":
            value = float(value)
        values.append(value)
    return json.dumps(values, ensure_ascii=False)


def answer_key(work: str, arguments: str, catalog: str) -> str:
    """Return the cache key of the answer of ``work`` to arguments whose ``canonical_key`` is ``arguments``."""
    text = json.dumps([work, arguments, catalog], ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


@contextmanager
def in_background() -> Iterator[None]:
    """Mark the work run inside as background work: it yields to every interactive request (``pool.turns``)."""
    with background():
        yield


@dataclass(frozen=True)
class Answer:
    """A worker's answer (a JSON-ready dict), whether it came from the cache, and how long it took."""

    data: dict[str, Any]
    cached: bool
    seconds: float


@dataclass(frozen=True)
class Workers:
    """The pools, the answer cache and what every call needs: the settings and the catalog's fingerprint."""

    interactive: PlannerPool
    """Requests someone waits for (``Pool.INTERACTIVE``); also starts the probe's throwaway process."""
    jobs: PlannerPool
    """Queued work's own workers, one per job runner (``Pool.JOBS``): no job takes an interactive worker."""
    settings: Settings
    cache: ResultCache
    catalog_key: str

    def run(
        self,
        work: Work[A, R],
        arguments: A,
        meanwhile: Callable[[], None] | None = None,
        stop: threading.Event | None = None,
    ) -> R:
        """Return ``work``'s function run on ``arguments`` in a worker of its pool, within its time limit.

        ``meanwhile`` (interactive work) runs once a worker is ours, while it works (e.g. storing
        the request's record), so a refused request runs nothing. ``stop`` (queued work) kills
        the worker once set: then this raises WorkStoppedError.

        Raises QueueFullError (429), PlanningTimeoutError (504), WorkerCrashedError (503), the
        ``CausalPlanError`` the work raised, or InternalError for a bug in it.
        """
        seconds = work.seconds(arguments, self.settings)
        call = (work.function, arguments, tuple(self.settings.catalog_folders))
        if work.pool is Pool.INTERACTIVE:
            result: R = self.interactive_call(call, seconds, meanwhile)
        elif work.pool is Pool.JOBS:
            result = self.queued_call(call, seconds, stop)
        else:
            result = self.interactive.run_isolated(perform, call, seconds)
        return result

    def interactive_call(
        self, call: tuple[Any, ...], seconds: float, meanwhile: Callable[[], None] | None = None
    ) -> Any:
        """Return ``perform(*call)`` from an interactive worker: every call of that pool passes here.

        Blocks while no worker is free: call it from a thread, never the event loop.
        """
        return self.interactive.run(perform, call, seconds, meanwhile)

    def queued_call(self, call: tuple[Any, ...], seconds: float, stop: threading.Event | None) -> Any:
        """Return ``perform(*call)`` from a worker of the jobs' pool (started with its first call).

        Queued work is not in a hurry: a full pool (QueueFullError) means wait and try again,
        not fail; a closed pool (the server stopping) raises WorkerCrashedError at once. Once
        ``stop`` is set, the worker is killed and this raises WorkStoppedError.
        """
        self.jobs.start_once()
        while True:
            try:
                return self.jobs.run(perform, call, seconds, stop=stop)
            except RunStoppedError:
                raise WorkStoppedError from None
            except QueueFullError as exc:
                if stop is None:
                    raise
                if stop.wait(exc.retry_after):
                    raise WorkStoppedError from None

    def answer(
        self, work: Work[A, dict[str, Any]], arguments: A, meanwhile: Callable[[], None] | None = None
    ) -> Answer:
        """Return the answer kept for ``work`` on ``arguments``, or run it (and keep it when final).

        Blocks while no worker is free: call it in a thread. ``meanwhile`` (e.g. storing the
        request's record) runs while the worker works, or first for a kept answer; not for a
        request refused before a worker took it.
        """
        started = time.perf_counter()
        key = answer_key(work.name, canonical_key(arguments), self.catalog_key)
        cached = self.cache.get(key)
        if cached is not None:
            if meanwhile is not None:
                meanwhile()
            return Answer(cached, True, time.perf_counter() - started)
        data = self.run(work, arguments, meanwhile)
        if work.is_final is not None and work.is_final(data):  # a timeout may go otherwise next time
            self.cache.put(key, data)
        return Answer(data, False, time.perf_counter() - started)

    def probe(self) -> dict[str, object]:
        """Return what a worker can run (planners, Fast Downward, optional backends), from a throwaway process."""
        return self.run(PROBE, ProbeArguments())
