"""The robot's films the app keeps: made by planner workers, kept by size, fetched by key.

A film is filmed once per object, plan, format and size (the robot is deterministic), so its
key is the hash of those and of the catalog. ``FilmStore.start`` films in the background
(a thread waits for the worker) and its progress is read from the file the worker writes;
``FilmStore.put`` keeps a film a request made itself. Least used films go first when the
bytes kept would pass the limit (``cachetools.LRUCache`` sized by bytes).
"""

from __future__ import annotations

import hashlib
import json
import logging
import tempfile
import threading
import time
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from cachetools import LRUCache

from causalplan.errors import CausalPlanError
from causalplan.service.errors import NotFoundError
from causalplan.service.pool.robot_jobs import CONTENT_TYPES, read_progress

logger = logging.getLogger(__name__)

FilmState = Literal["filming", "ready", "failed"]
FILM_OVERHEAD_BYTES = 1024
"""What a film's record counts beyond its video (so films still being made count too)."""


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
    """One film: being made, made, or failed; its bytes once made."""

    key: str
    video: str
    state: FilmState
    progress_file: Path | None = None
    data: bytes = b""
    robot: dict[str, Any] | None = None
    """Whether the robot carried out the plan (``robot_jobs.robot_outcome``), once filmed."""
    error: dict[str, str] | None = None
    started: float = field(default_factory=time.monotonic)
    seconds: float | None = None

    @property
    def content_type(self) -> str:
        """Return the film's media type."""
        return CONTENT_TYPES[self.video]

    def status(self) -> dict[str, Any]:
        """Return what a page polling the film shows: its state, frames drawn and expected, seconds, outcome."""
        frames, expected = (0, None)
        if self.state == "filming" and self.progress_file is not None:
            frames, expected = read_progress(self.progress_file)
        seconds = self.seconds if self.seconds is not None else time.monotonic() - self.started
        return {
            "state": self.state,
            "frames": frames,
            "expected_frames": expected,
            "seconds": round(seconds, 1),
            "robot": self.robot,
            "error": self.error,
            "content_type": self.content_type,
            "bytes": len(self.data),
        }


def _size(film: Film) -> int:
    return len(film.data) + FILM_OVERHEAD_BYTES


class FilmStore:
    """Films by key, at most ``max_bytes`` of them; safe to share between threads."""

    def __init__(self, max_bytes: int) -> None:
        self.max_bytes = max_bytes
        self._films: LRUCache[str, Film] = LRUCache(maxsize=max_bytes, getsizeof=_size)
        self._lock = threading.Lock()
        self._folder = tempfile.TemporaryDirectory(prefix="causalplan-films-")
        weakref.finalize(self, self._folder.cleanup)

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
        """Return whether a film (made or being made) is kept under ``key``."""
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
        film = Film(key, video, "ready", data=data, robot=robot, seconds=0.0)
        self._keep(film)
        return film

    def start(self, key: str, video: str, make: Callable[[Path], dict[str, Any]]) -> Film:
        """Return the film under ``key``, starting to make it (``make(progress_file)``, in a thread) when new or failed.

        ``make`` returns ``{"video": bytes, "robot": ...}`` and may raise ``CausalPlanError``
        (the film then fails with its code and message).
        """
        with self._lock:
            film = self._films.get(key)
            if film is not None and film.state != "failed":
                return film
            film = Film(key, video, "filming", progress_file=Path(self._folder.name) / f"{key}.json")
            self._films[key] = film
        threading.Thread(target=self._make, args=(film, make), name=f"film-{key[:8]}", daemon=True).start()
        return film

    def _make(self, film: Film, make: Callable[[Path], dict[str, Any]]) -> None:
        assert film.progress_file is not None
        try:
            made = make(film.progress_file)
        except CausalPlanError as exc:
            film.error = {"code": exc.code, "message": exc.message}
            film.state = "failed"
        except Exception:  # a bug must not leave the film "filming" for ever
            logger.exception("filming %s failed", film.key)
            film.error = {"code": "internal_error", "message": "The film could not be made; the server log says why."}
            film.state = "failed"
        else:
            film.robot = made.get("robot")
            video = made.get("video")
            if isinstance(video, bytes):
                film.data, film.state = video, "ready"
            else:
                film.error = {"code": "no_video", "message": "The robot made no film of this plan."}
                film.state = "failed"
        film.seconds = time.monotonic() - film.started
        film.progress_file.unlink(missing_ok=True)
        with self._lock:
            if film.key in self._films:
                del self._films[film.key]  # put back with its real size
        self._keep(film)
