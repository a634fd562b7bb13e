"""The tests mirror the package: a module's tests are found by its path.

``causalplan/service/pages/participant.py`` is tested in ``tests/service/pages/``; a test file
at the top of ``tests/`` tests a top-level module (``causalplan/api.py``) or the project as a
whole (its imports, its containers, a fresh machine).
"""

from __future__ import annotations

from pathlib import Path

TESTS = Path(__file__).resolve().parent
PACKAGE = TESTS.parent / "causalplan"
PROJECT_FOLDERS = {"benchmarks"}
"""Folders of the repository beside the package whose code has tests of its own (``tests/benchmarks/``)."""

# What the top-level test files check that is not one module: the project as a whole.
PROJECT_WIDE = {
    "test_architecture.py",
    "test_imports.py",
    "test_docker.py",
    "test_fresh_machine.py",
    "test_layout.py",
    "test_scheduler.py",
}


def test_every_test_folder_is_a_package_folder() -> None:
    folders = {path.parent for path in TESTS.rglob("test_*.py")} - {TESTS}
    strays = sorted(
        str(folder.relative_to(TESTS))
        for folder in folders
        if not (PACKAGE / folder.relative_to(TESTS)).is_dir()
        and folder.relative_to(TESTS).parts[0] not in PROJECT_FOLDERS
    )
    assert strays == [], f"test folders with no package folder of the same path: {strays}"


def test_top_level_test_files_test_top_level_modules() -> None:
    strays = sorted(
        path.name
        for path in TESTS.glob("test_*.py")
        if path.name not in PROJECT_WIDE and not (PACKAGE / path.name.removeprefix("test_")).is_file()
    )
    assert strays == [], f"top-level test files for no top-level module (move each into its package's folder): {strays}"


def test_every_test_folder_is_importable_as_a_package() -> None:
    """Without ``__init__.py``, two ``test_runner.py`` in different folders would clash under pytest."""
    missing = sorted(
        str(folder.relative_to(TESTS))
        for folder in {path.parent for path in TESTS.rglob("*.py")}
        if not (folder / "__init__.py").is_file() and folder.name != "__pycache__"
    )
    assert missing == [], f"test folders without __init__.py: {missing}"
