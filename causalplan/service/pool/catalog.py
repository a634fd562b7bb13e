"""The catalog a worker process reads once: every call a worker serves shares it."""

from __future__ import annotations

from functools import cache
from pathlib import Path

from causalplan.objects.catalog import Catalog, load_catalog


@cache
def worker_catalog(folders: tuple[Path, ...]) -> Catalog:
    """Return the catalog with the objects in ``folders``, read once per worker process."""
    return load_catalog(folders)
