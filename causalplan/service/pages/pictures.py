"""Keeping the pages' pictures, and a plain one when the simulator cannot draw.

The simulator draws in a worker process (``work.pictures``: PyBullet never loads in the web
server); ``PictureCache`` keeps what it drew in the server (the app's caches, ``service.caches``),
since the same pictures are asked for again and again. When the simulator cannot draw (busy,
missing), ``drawing`` gives a plain picture with the part's name instead.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from xml.sax.saxutils import escape

from causalplan.caches import BoundedCache
from causalplan.service.work.pictures import PART_PICTURE_SIZE


def drawing(name: str, width: int = PART_PICTURE_SIZE[0], height: int = PART_PICTURE_SIZE[1]) -> bytes:
    """Return a plain SVG picture with ``name`` in it (when the simulator cannot draw)."""
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}" role="img">'
        f'<rect x="8" y="8" width="{width - 16}" height="{height - 16}" rx="12" fill="#f4efe4" stroke="#8a7f6a"/>'
        f'<text x="{width / 2}" y="{height / 2}" text-anchor="middle" dominant-baseline="middle" '
        f'font-family="sans-serif" font-size="20" fill="#333">{escape(name)}</text></svg>'
    ).encode()


class PictureCache:
    """The ``size`` pictures last used (a ``BoundedCache``); one drawing per key at a time (others wait)."""

    def __init__(self, size: int) -> None:
        self._pictures: BoundedCache[str, bytes] = BoundedCache(size)
        self._lock = threading.Lock()
        self._drawing: dict[str, threading.Lock] = {}

    def clear(self) -> None:
        """Forget every kept picture (the next request for one draws it again)."""
        self._pictures.clear()

    def stats(self) -> dict[str, int]:
        """Return the size, pictures kept, hits and misses."""
        return self._pictures.stats()

    def has(self, key: str) -> bool:
        """Return whether the picture of ``key`` is kept (without making it the last used)."""
        return self._pictures.has(key)

    def get(self, key: str, draw: Callable[[], dict[str, bytes]]) -> bytes | None:
        """Return the picture of ``key``; ``draw`` makes it (and maybe others) when it is not kept yet.

        Returns None when ``draw`` did not make ``key``. Errors of ``draw`` go to the caller,
        and nothing is kept, so the next request tries again.
        """
        picture = self._pictures.get(key)
        if picture is not None:
            return picture
        with self._lock:
            drawing_lock = self._drawing.setdefault(key, threading.Lock())
        with drawing_lock:
            if self._pictures.has(key):  # drawn while this request waited (its miss is counted once, above)
                return self._pictures.get(key)
            try:
                drawn = draw()
                self._pictures.update(drawn)
            finally:
                with self._lock:
                    self._drawing.pop(key, None)
            return drawn.get(key)
