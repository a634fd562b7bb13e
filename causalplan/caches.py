"""The process's caches, with one owner: each named and bounded, counted, and replaced in one call.

Every cache here keeps the answer of deterministic work under a key that names everything the
answer depends on (the canonical form its caller computes: PDDL texts, a checked plan, the
object itself), so a kept answer never goes stale; a size bounds each (least recently used
out first), and none needs a time to live. ``current()`` is the process's owner; ``fresh()``
puts an empty one in its place: the one call tests (one fixture) and worker processes (at their
start) make instead of a reset hook per module. The service's own caches belong to its app
(``service.caches``, held by ``Services``).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass, field, fields
from typing import Any, Generic, Protocol, TypeVar

from cachetools import LRUCache

K = TypeVar("K", bound=Hashable)
V = TypeVar("V")


class BoundedCache(Generic[K, V]):
    """The ``size`` values last used, by key (``cachetools.LRUCache``), counting hits and misses; thread-safe.

    Size 0 keeps nothing (every ``get`` misses).
    """

    def __init__(self, size: int) -> None:
        if size < 0:
            raise ValueError(f"a cache's size is 0 or more, not {size}")
        self.size = size
        self._entries: LRUCache[K, V] = LRUCache(maxsize=max(size, 1))
        self._lock = threading.Lock()  # cachetools' caches are not thread-safe, and a read reorders an LRU
        self.hits = 0
        self.misses = 0

    def get(self, key: K) -> V | None:
        """Return the value kept for ``key`` (now the last used), or None."""
        with self._lock:
            value = self._entries.get(key)
            if value is None:
                self.misses += 1
            else:
                self.hits += 1
            return value

    def has(self, key: K) -> bool:
        """Return whether a value is kept for ``key``, without using it (no count, no reordering)."""
        with self._lock:
            return key in self._entries

    def put(self, key: K, value: V) -> None:
        """Keep ``value`` for ``key`` (the least recently used goes when full; nothing with size 0)."""
        self.update({key: value})

    def update(self, values: Mapping[K, V]) -> None:
        """Keep every value of ``values`` by its key."""
        if self.size == 0:
            return
        with self._lock:
            self._entries.update(values)

    def get_or_make(self, key: K, make: Callable[[], V], keep: Callable[[V], bool] = lambda _: True) -> V:
        """Return the value kept for ``key``, else ``make()``, kept when ``keep`` says so.

        ``make`` runs outside the lock: two threads missing one key at once may both make it.
        """
        value = self.get(key)
        if value is None:
            value = make()
            if keep(value):
                self.put(key, value)
        return value

    def clear(self) -> None:
        """Forget every value (the counts stay)."""
        with self._lock:
            self._entries.clear()

    def __len__(self) -> int:
        with self._lock:
            return len(self._entries)

    def stats(self) -> dict[str, int]:
        """Return the size, entries kept, hits and misses."""
        with self._lock:
            return {"size": self.size, "entries": len(self._entries), "hits": self.hits, "misses": self.misses}


class Counted(Protocol):
    """A cache an owner can count and clear."""

    def stats(self) -> dict[str, int]: ...

    def clear(self) -> None: ...


class NamedCaches:
    """What an owner of caches (a dataclass whose every field is a cache) offers: by name, counted, cleared."""

    def named(self) -> list[tuple[str, Counted]]:
        """Return every cache with its name."""
        return [(each.name, getattr(self, each.name)) for each in fields(self)]  # type: ignore[arg-type]

    def stats(self) -> dict[str, dict[str, int]]:
        """Return each cache's size, entries, hits and misses, by name."""
        return {name: cache.stats() for name, cache in self.named()}

    def clear(self) -> None:
        """Forget every kept value."""
        for _, cache in self.named():
            cache.clear()


FD_ANSWERS = 512
VAL_VERDICTS = 1024
SIMULATIONS = 256
ROBOT_RUNS = 256
SOLIDS = 64
SYNTHETIC_OBJECTS = 64
LABEL_EMBEDDINGS = 4096


@dataclass(frozen=True)
class Caches(NamedCaches):
    """Every cache of the process by name; a new one is empty. Values are typed where they are used."""

    fd_answers: BoundedCache[tuple[str, str, str], Any] = field(default_factory=lambda: BoundedCache(FD_ANSWERS))
    """Fast Downward's definite answers (a plan, or proof there is none), by search and PDDL texts (``fd.solve``)."""
    val_verdicts: BoundedCache[tuple[Hashable, str], Any] = field(default_factory=lambda: BoundedCache(VAL_VERDICTS))
    """VAL's verdicts, by the task's canonical form and the plan's text (``planners.val``)."""
    simulations: BoundedCache[tuple[Hashable, ...], Any] = field(default_factory=lambda: BoundedCache(SIMULATIONS))
    """The simulator's reports of a plan (no pictures), by object and checked steps (``transfer.verdict``)."""
    robot_runs: BoundedCache[tuple[Hashable, ...], Any] = field(default_factory=lambda: BoundedCache(ROBOT_RUNS))
    """The robot's runs of a plan, by object and checked steps (``transfer.robot_verdict``)."""
    solids: BoundedCache[Any, Any] = field(default_factory=lambda: BoundedCache(SOLIDS))
    """Each object's parts as solids, by object (``sim.geometry.solids``)."""
    synthetic_objects: BoundedCache[tuple[int, int], Any] = field(
        default_factory=lambda: BoundedCache(SYNTHETIC_OBJECTS)
    )
    """Seeded synthetic objects, by size and seed (``comparison.synthetic``)."""
    label_embeddings: BoundedCache[str, Any] = field(default_factory=lambda: BoundedCache(LABEL_EMBEDDINGS))
    """Unit-length sentence embeddings of labels, by text (``consensus.embedding``)."""

    @classmethod
    def sized(cls, sizes: Mapping[str, int]) -> Caches:
        """Return an empty owner whose caches named in ``sizes`` keep that many values (the others their default)."""
        names = {each.name for each in fields(cls)}
        unknown = sorted(set(sizes) - names)
        if unknown:
            raise ValueError(f"no cache named {', '.join(unknown)}; the caches are: {', '.join(sorted(names))}")
        made: dict[str, BoundedCache[Any, Any]] = {name: BoundedCache(size) for name, size in sizes.items()}
        return cls(**made)


_owner = [Caches()]
"""The process's owner: the only cache held by a module (a list, so ``fresh`` needs no ``global``)."""


def current() -> Caches:
    """Return the process's caches."""
    return _owner[0]


def fresh(sizes: Mapping[str, int] | None = None) -> Caches:
    """Make an empty owner the process's (with ``sizes`` by cache name, see ``Caches.sized``) and return it.

    The one entry point to forget every cached answer: tests (one fixture), benchmarks that
    time real runs, and a worker process at its start (with its settings' sizes).
    """
    owner = Caches.sized(sizes or {})
    _owner[0] = owner
    return owner
