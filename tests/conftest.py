"""Shared fixtures: the catalog, the examples folder, and loaders for example files."""

from __future__ import annotations

import ast
import os
import re
from functools import cache
from pathlib import Path
from typing import Any

import pytest

from causalplan import caches
from causalplan.caches import Caches
from causalplan.causal.model import CausalModel, Labelling
from causalplan.inputs import load_mapping, load_model
from causalplan.objects.catalog import Catalog, load_catalog

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

pytest_plugins = ["tests.service.fixtures"]  # the HTTP service's apps, databases and PostgreSQL server


def pytest_configure(config: pytest.Config) -> None:
    """Keep the catalog's disk cache (``objects.cache``) in pytest's cache folder, not the home folder."""
    cache = getattr(config, "cache", None)  # absent with -p no:cacheprovider: the default folder then
    if cache is not None:
        os.environ.setdefault("CAUSALPLAN_CACHE_DIR", str(cache.mkdir("causalplan-objects")))


WHOLLY_SLOW = re.compile(r"^pytestmark = pytest\.mark\.slow\b", re.MULTILINE)


def pytest_ignore_collect(collection_path: Path, config: pytest.Config) -> bool | None:
    """In the fast lane (``-m "not slow"``), do not import the modules marked slow as a whole.

    Each xdist worker would import them only to deselect every test: their imports and
    module-level set-up (schemathesis builds a case per route, the browser and robot modules
    load their libraries) cost each worker seconds.
    """
    fast_lane = config.getoption("markexpr", "").replace(" ", "") == "notslow"
    if fast_lane and collection_path.suffix == ".py" and collection_path.name.startswith("test_"):
        return WHOLLY_SLOW.search(collection_path.read_text(encoding="utf-8")) is not None or None
    return None


def _module_fixtures(tree: ast.Module) -> set[str]:
    """Return the names of the module-scoped fixtures a test file (or fixtures file) defines."""
    return {
        node.name
        for node in ast.walk(tree)
        if isinstance(node, ast.FunctionDef)
        for decorator in node.decorator_list
        if isinstance(decorator, ast.Call)
        and any(
            keyword.arg == "scope" and isinstance(keyword.value, ast.Constant) and keyword.value.value == "module"
            for keyword in decorator.keywords
        )
    }


@cache
def _shared_module_fixtures() -> set[str]:
    """Return the module-scoped fixtures of ``service/fixtures.py``, which many test files import."""
    return _module_fixtures(ast.parse((Path(__file__).parent / "service" / "fixtures.py").read_text(encoding="utf-8")))


@cache
def shares_a_module_fixture(path: Path) -> bool:
    """Return whether a test of this file asks for a module-scoped fixture (most start an app)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names = _shared_module_fixtures() | _module_fixtures(tree)
    tests = [node for node in ast.walk(tree) if isinstance(node, ast.FunctionDef) and node.name.startswith("test_")]
    return any({arg.arg for arg in test.args.args} & names for test in tests)


@pytest.hookimpl(tryfirst=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """Deal tests to xdist's workers one by one, but a file's together when they share a module-scoped fixture.

    Such a fixture mostly starts an app (its planner workers, its database): dealt one by one,
    a file's tests would make each worker start the file's app again. Only for ``--dist load``
    (what ``-n`` means); another ``--dist`` keeps xdist's own scheduler.
    """
    if config.getoption("dist") != "load":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class ByFileWhereShared(LoadScopeScheduling):  # type: ignore[misc]
        def _split_scope(self, nodeid: str) -> str:
            file = nodeid.split("::", 1)[0]
            shared = file.endswith(".py") and shares_a_module_fixture(config.rootpath / file)
            return file if shared else nodeid

        # xdist 3.8 breaks when a worker crashes (a segfault): the run ends in an INTERNALERROR
        # that names no test (pytest-xdist #1362, #1323, open). Mended here as their fixes do.
        def remove_node(self, node: Any) -> str | None:
            """Forget a dead worker's collection; queue again only its work not done, less the crashed test.

            A worker that finished its work keeps its collection: the run is complete only while
            every worker's is registered.
            """
            workload = self.assigned_work.pop(node)
            pending = {scope: unit for scope, unit in workload.items() if not all(unit.values())}
            if not pending:
                return None
            self.registered_collections.pop(node, None)  # it crashed: its replacement registers its own
            crashed = next(nodeid for unit in pending.values() for nodeid, done in unit.items() if not done)
            pending[self._split_scope(crashed)][crashed] = True  # reported as crashed, not run again
            self.workqueue.update({scope: unit for scope, unit in pending.items() if not all(unit.values())})
            for other in self.assigned_work:
                self._reschedule(other)
            return crashed

        def _reschedule(self, node: Any) -> None:
            if node in self.registered_collections:  # a replacement still collecting gets work when it is done
                super()._reschedule(node)

    return ByFileWhereShared(config, log)


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
