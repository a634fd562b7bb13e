"""causalplan's version: the installed package's, read once from its metadata (``pyproject.toml`` sets it)."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("causalplan")
except PackageNotFoundError:  # a source tree used without installing it: no metadata to read
    __version__ = "0+unknown"
