"""Pictures for the pages, drawn by the simulator: each part of an object, and an object after a plan.

The jobs here run in a planner worker process (PyBullet never loads in the web server);
``PictureCache`` keeps what they drew in the server (the app's caches, ``service.caches``),
since a picture runs the simulator and the same pictures are asked for again and again. When
the simulator cannot draw (busy, missing), ``drawing`` gives a plain picture with the part's
name instead.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path
from xml.sax.saxutils import escape

from causalplan.caches import BoundedCache
from causalplan.service.pool.catalog import worker_catalog

PART_PICTURE_SIZE = (320, 240)
PLAN_PICTURE_SIZE = (480, 360)


def part_pictures_job(object_id: str, catalog_folders: tuple[Path, ...]) -> dict[str, bytes]:
    """Return a PNG of each part of an object, alone on the table (runs in a worker)."""
    from causalplan.sim.geometry import solids
    from causalplan.sim.poses import Pose
    from causalplan.sim.render import Camera, draw
    from causalplan.sim.scene import Scene

    obj = worker_catalog(catalog_folders).get(object_id)
    pictures: dict[str, bytes] = {}
    for part_id, solid in solids(obj).items():
        with Scene({part_id: solid}) as scene:
            # Centred on the table, standing on it.
            pose = Pose(
                (-(solid.lower[0] + solid.upper[0]) / 2, -(solid.lower[1] + solid.upper[1]) / 2, -solid.lower[2])
            )
            scene.add_part(part_id, pose, dynamic=False)
            camera = Camera.around(scene, pose.apply(solid.lower), pose.apply(solid.upper), size=PART_PICTURE_SIZE)
            pictures[part_id] = draw(scene, camera, (), "").png()
    return pictures


def assembly_picture_job(object_id: str, fit_ids: tuple[str, ...], catalog_folders: tuple[Path, ...]) -> bytes:
    """Return a PNG of the object after the plan that makes ``fit_ids`` in order (runs in a worker)."""
    from causalplan.sim import RenderMode, StepRequest, simulate_plan

    obj = worker_catalog(catalog_folders).get(object_id)
    steps = [StepRequest(fit.primitive, fit.moving_part, fit.fixed_part, fit.id) for fit in map(obj.fit, fit_ids)]
    report = simulate_plan(obj, steps, render=RenderMode.FINAL, size=PLAN_PICTURE_SIZE)
    assert report.picture is not None, "RenderMode.FINAL always draws the final picture"
    return report.picture.png()


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
