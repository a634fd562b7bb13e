"""A disk cache of checked catalog objects, so a command does not re-validate unchanged files.

Each entry is the pickled ``AssemblyObject`` of one object file, named by a hash of the file's
exact text, the causalplan version and the code that builds objects: an edited file, a new
causalplan, or an edit to that code (an editable install keeps its version) misses the cache.
Only files that passed every check are stored. The folder is ``CAUSALPLAN_CACHE_DIR``, else the
user cache folder ``platformdirs`` gives (``~/.cache/causalplan`` on Linux, honouring
``XDG_CACHE_HOME``); ``CAUSALPLAN_CACHE_DIR=off`` turns it off. A cache that cannot be read or
written is ignored (it only costs time).
"""

from __future__ import annotations

import functools
import hashlib
import logging
import os
import pickle
import tempfile
from collections.abc import Callable
from pathlib import Path

import platformdirs

from causalplan.objects.model import AssemblyObject
from causalplan.version import __version__

logger = logging.getLogger(__name__)


def configured_folder() -> str | None:
    """Return ``CAUSALPLAN_CACHE_DIR`` (a folder, or "off"), if set: the one place this module reads it."""
    return os.environ.get("CAUSALPLAN_CACHE_DIR") or None


def cache_folder() -> Path | None:
    """Return the cache folder, or None when caching is off."""
    configured = configured_folder()
    if configured == "off":
        return None
    if configured:
        return Path(configured)
    return Path(platformdirs.user_cache_dir("causalplan", appauthor=False))


BUILDING_MODULES = ("catalog.py", "model.py", "schema.py", "shapes.py")
"""The modules of this package that turn an object file's text into an ``AssemblyObject``."""


@functools.cache
def _code_version() -> bytes | None:
    """Return a hash of the causalplan version and of the code that builds objects (None if unreadable)."""
    digest = hashlib.sha256(__version__.encode())
    try:
        for name in BUILDING_MODULES:
            digest.update(Path(__file__).with_name(name).read_bytes())
    except OSError as exc:
        logger.debug("catalog cache off: cannot read the code that builds objects: %s", exc)
        return None
    return digest.digest()


def _entry(text: str) -> Path | None:
    folder = cache_folder()
    code = _code_version()
    if folder is None or code is None:
        return None
    digest = hashlib.sha256(code + text.encode()).hexdigest()[:32]
    return folder / f"object-{digest}.pickle"


def cached_object(text: str, parse: Callable[[], AssemblyObject]) -> AssemblyObject:
    """Return the object of a file's ``text``: from the cache, or ``parse()`` it and store it."""
    entry = _entry(text)
    if entry is not None:
        try:
            loaded = pickle.loads(entry.read_bytes())
            if isinstance(loaded, AssemblyObject):
                return loaded
        except FileNotFoundError:
            pass
        except Exception as exc:  # noqa: BLE001 - a damaged or stale entry is re-made, never trusted
            logger.debug("ignoring catalog cache entry %s: %s", entry, exc)
    obj = parse()
    if entry is not None:
        try:
            entry.parent.mkdir(parents=True, exist_ok=True)
            with tempfile.NamedTemporaryFile(dir=entry.parent, delete=False, suffix=".tmp") as handle:
                handle.write(pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))
            os.replace(handle.name, entry)
        except OSError as exc:
            logger.debug("cannot write catalog cache entry %s: %s", entry, exc)
    return obj
