"""The robot's films a POST /v1/simulations with ``video`` made: kept by size in this replica, fetched by key.

A film is filmed once per object, plan, format and size (the robot is deterministic), so its
key is the hash of those and of the catalog. Least used films go first when the bytes kept
would pass the limit (``cachetools.LRUCache`` sized by bytes). These stay in the replica that
made them, like the answer that names them; a film to follow and fetch from any replica is a
``video`` job (``service.jobs.video``), which is how the participant page films.
"""

from __future__ import annotations

import hashlib
import json
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

from cachetools import LRUCache

from causalplan.service.errors import NotFoundError
from causalplan.service.pool.robot_jobs import CONTENT_TYPES

FilmState = Literal["ready", "failed"]
FILM_OVERHEAD_BYTES = 1024
"""What a film's record counts beyond its video."""


class FilmNotFoundError(NotFoundError):
    """No film is kept under this key (never made, or let go to make room)."""

    code = "video_not_found"


def film_key(catalog_key: str, object_id: str, fit_ids: Sequence[str], video: str, size: tuple[int, int]) -> str:
    """Return the key of the film of the plan making ``fit_ids`` of the object, in ``video`` format and ``size``."""
    text = json.dumps([catalog_key, object_id, list(fit_ids), video, list(size)], ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:32]


def video_url(key: str) -> str:
    """Return where the API serves the film kept under ``key``."""
    return f"/v1/simulations/videos/{key}"


@dataclass
class Film:
    """One film: made (its bytes), or failed (too large to keep)."""

    key: str
    video: str
    state: FilmState
    data: bytes = b""
    robot: dict[str, Any] | None = None
    """Whether the robot carried out the plan (``robot_jobs.robot_outcome``)."""
    error: dict[str, str] | None = None

    @property
    def content_type(self) -> str:
        """Return the film's media type."""
        return CONTENT_TYPES[self.video]


def _size(film: Film) -> int:
    return len(film.data) + FILM_OVERHEAD_BYTES


class FilmStore:
    """Films by key, at most ``max_bytes`` of them; safe to share between threads."""

    def __init__(self, max_bytes: int) -> None:
        self.max_bytes = max_bytes
        self._films: LRUCache[str, Film] = LRUCache(maxsize=max_bytes, getsizeof=_size)
        self._lock = threading.Lock()

    def get(self, key: str) -> Film:
        """Return the film kept under ``key``; FilmNotFoundError when there is none."""
        with self._lock:
            film = self._films.get(key)
        if film is None:
            raise FilmNotFoundError(
                f"No video is kept under '{key}': never made here, or let go to make room; ask for it again.",
                details={"key": key},
            )
        return film

    def has(self, key: str) -> bool:
        """Return whether a film is kept under ``key``."""
        with self._lock:
            return key in self._films

    def _keep(self, film: Film) -> None:
        with self._lock:
            if _size(film) > self.max_bytes:  # larger than the whole store: keep its outcome, not its bytes
                film.data, film.state = b"", "failed"
                film.error = {"code": "video_too_large", "message": "The video is larger than the server keeps."}
            self._films[film.key] = film

    def put(self, key: str, video: str, data: bytes, robot: dict[str, Any] | None = None) -> Film:
        """Keep a film made elsewhere; return it."""
        film = Film(key, video, "ready", data=data, robot=robot)
        self._keep(film)
        return film
