"""Shared fixtures: the catalog, the examples folder, and loaders for example files."""

from __future__ import annotations

import os
from functools import cache
from pathlib import Path

import pytest

from causalplan import caches
from causalplan.caches import Caches
from causalplan.causal.model import CausalModel, Labelling
from causalplan.inputs import load_mapping, load_model
from causalplan.objects.catalog import Catalog, load_catalog

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

pytest_plugins = ["tests.service_fixtures"]  # the HTTP service's apps, databases and PostgreSQL server


def pytest_configure(config: pytest.Config) -> None:
    """Keep the catalog's disk cache (``objects.cache``) in pytest's cache folder, not the home folder."""
    cache = getattr(config, "cache", None)  # absent with -p no:cacheprovider: the default folder then
    if cache is not None:
        os.environ.setdefault("CAUSALPLAN_CACHE_DIR", str(cache.mkdir("causalplan-objects")))


@cache
def builtin_catalog() -> Catalog:
    """Return the built-in catalog, loaded once per run (the ``catalog`` fixture, for module-level use)."""
    return load_catalog()


@pytest.fixture(scope="session")
def catalog() -> Catalog:
    return builtin_catalog()


@pytest.fixture(scope="session")
def user_catalog() -> Catalog:
    return load_catalog([EXAMPLES / "catalog"])


def example_model(relative: str, catalog: Catalog) -> CausalModel:
    """Return a valid example model (asserting it is valid)."""
    loaded = load_model(EXAMPLES / relative, catalog)
    assert loaded.is_valid, loaded.report.as_dict()
    assert loaded.model is not None
    return loaded.model


def example_mapping(relative: str, catalog: Catalog) -> Labelling:
    """Return a valid example mapping (asserting it is valid)."""
    loaded = load_mapping(EXAMPLES / relative, catalog)
    assert loaded.is_valid, loaded.report.as_dict()
    assert loaded.mapping is not None
    return loaded.mapping


@pytest.fixture(autouse=True)
def process_caches() -> Caches:
    """Give every test an empty owner of the process's caches, so runs are real unless a test repeats them."""
    return caches.fresh()
