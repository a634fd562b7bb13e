"""The package's import graph: no cycle between modules or packages, and ``studies`` free of the web.

Every import counts, inside functions and in ``__init__`` files too: the graph is read from the
source with ``ast``, not from what one run happens to import.
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx

ROOT = Path(__file__).resolve().parent.parent / "causalplan"
WEB_FRAMEWORKS = ("fastapi", "starlette", "jinja2")


def module_name(path: Path) -> str:
    """Return the dotted name of a source file of the package (a package's ``__init__`` is the package)."""
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict[str, Path]:
    """Return every module of the package by its dotted name."""
    return {module_name(path): path for path in sorted(ROOT.rglob("*.py"))}


def imported_names(source: str, package: str) -> set[str]:
    """Return every dotted name ``source`` imports, anywhere in it (``from a import b``: ``a`` and ``a.b``)."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # a relative import, from the importing module's package
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names)
    return names


def imports_of(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """Return the modules of the package that module ``name`` imports.

    ``from a import b`` imports the module ``a.b`` when there is one, else the name ``b`` of ``a``.
    """
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    names = imported_names(path.read_text(encoding="utf-8"), package)
    found = set()
    for target in names:
        if target not in known or target == name:
            continue
        if any(other.startswith(target + ".") and other in known for other in names):
            continue  # ``from a import b`` with ``a.b`` a module: the edge goes to ``a.b``
        found.add(target)
    return found


def module_graph() -> nx.DiGraph:
    """Return the graph of the package's modules: an edge from each module to each module it imports."""
    known = modules()
    graph = nx.DiGraph()
    graph.add_nodes_from(known)
    for name, path in known.items():
        graph.add_edges_from((name, target) for target in imports_of(name, path, known))
    return graph


def package_of(module: str) -> str:
    """Return the subpackage (or top-level module) a module is in: ``causalplan.sim.robot`` -> ``causalplan.sim``."""
    return ".".join(module.split(".")[:2])


def package_graph(modules_graph: nx.DiGraph) -> nx.DiGraph:
    """Return the graph of the subpackages: an edge where a module of one imports a module of another."""
    graph = nx.DiGraph()
    graph.add_edges_from(
        (package_of(source), package_of(target))
        for source, target in modules_graph.edges
        if package_of(source) != package_of(target)
    )
    return graph


def test_no_module_imports_itself_through_others() -> None:
    assert sorted(nx.simple_cycles(module_graph())) == []


def test_no_package_imports_itself_through_others() -> None:
    assert sorted(nx.simple_cycles(package_graph(module_graph()))) == []


def test_studies_import_no_web_framework_and_nothing_of_the_service() -> None:
    known = modules()
    offending = {
        name: sorted(
            target
            for target in imported_names(path.read_text(encoding="utf-8"), name)
            if target.split(".")[0] in WEB_FRAMEWORKS or target.startswith(("causalplan.service", "causalplan.cli"))
        )
        for name, path in known.items()
        if name.startswith("causalplan.studies")
    }
    assert {name: found for name, found in offending.items() if found} == {}


def test_an_import_inside_a_function_counts() -> None:
    source = "def page() -> None:\n    from fastapi import Request\n    import jinja2\n"
    assert imported_names(source, "causalplan.studies") == {"fastapi", "fastapi.Request", "jinja2"}


def test_a_relative_import_is_read_from_its_package() -> None:
    assert imported_names("from . import design\nfrom ..errors import X\n", "causalplan.studies") == {
        "causalplan.studies",
        "causalplan.studies.design",
        "causalplan.errors",
        "causalplan.errors.X",
    }


def test_a_circle_of_two_packages_is_a_cycle() -> None:
    modules_graph = nx.DiGraph([("causalplan.sim.robot", "causalplan.transfer.verdict")])
    modules_graph.add_edge("causalplan.transfer.batch", "causalplan.sim.executor")
    assert sorted(sorted(cycle) for cycle in nx.simple_cycles(package_graph(modules_graph))) == [
        ["causalplan.sim", "causalplan.transfer"]
    ]


POOL = "causalplan.service.pool"
WORK_LAYER = "causalplan.service.work"
APP_WIRING = ("causalplan.service.main", "causalplan.service.deps", "causalplan.service.fair_share")
"""The app's wiring: it starts and stops the pools and holds them (``Services``); the fair share is the
interactive pool with each client's turn taken first (``FairSharePool``)."""


def pool_importers(graph: nx.DiGraph) -> list[str]:
    """Return the modules outside the pool, the work layer and the app's wiring that import the pool."""
    inside = (POOL, WORK_LAYER)
    return sorted(
        source
        for source, target in graph.edges
        if (target == POOL or target.startswith(POOL + "."))
        and not any(source == place or source.startswith(place + ".") for place in inside)
        and source not in APP_WIRING
    )


def test_only_the_work_layer_and_the_app_s_wiring_import_the_pool() -> None:
    assert pool_importers(module_graph()) == []


def test_a_route_that_calls_the_pool_itself_is_found() -> None:
    graph = module_graph()
    graph.add_edge("causalplan.service.api.routes.plans", "causalplan.service.pool.pool")
    graph.add_edge("causalplan.service.work.calls", "causalplan.service.pool.pool")
    assert pool_importers(graph) == ["causalplan.service.api.routes.plans"]


STORAGE = "causalplan.service.storage"
QUERY_BUILDERS = {"select", "insert", "update", "delete", "text", "func"}
"""SQLAlchemy's ways to write a query: only ``service/storage/`` imports them."""
SESSION_WRITES = {"add", "add_all", "flush", "commit", "execute", "scalar", "scalars", "merge", "delete"}
"""What a session or connection runs against the database: only ``service/storage/`` calls them."""


def sql_in(source: str) -> list[str]:
    """Return the SQL a module writes or runs itself: query builders it imports, session calls it makes."""
    found: list[str] = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "sqlalchemy":
            found.extend(f"import {alias.name}" for alias in node.names if alias.name in QUERY_BUILDERS)
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr in SESSION_WRITES
            and isinstance(node.func.value, ast.Name)
            and node.func.value.id in ("session", "connection")
        ):
            found.append(f"{node.func.value.id}.{node.func.attr}")
    return found


def test_all_sql_lives_in_the_storage_layer() -> None:
    offending = {
        name: sql_in(path.read_text(encoding="utf-8"))
        for name, path in modules().items()
        if name != STORAGE and not name.startswith(STORAGE + ".")
    }
    assert {name: found for name, found in offending.items() if found} == {}


def test_a_query_outside_storage_is_found() -> None:
    source = "from sqlalchemy import select, text\n\ndef f(session):\n    session.add(1)\n    session.commit()\n"
    assert sql_in(source) == ["import select", "import text", "session.add", "session.commit"]
