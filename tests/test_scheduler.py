"""The suite's own xdist scheduler (``conftest.pytest_xdist_make_scheduler``), run by xdist itself."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

CONFTEST = "from tests.conftest import pytest_xdist_make_scheduler  # noqa: F401\n"
TESTS = """
import os
import signal

import pytest


@pytest.mark.parametrize("number", range(12))
def test_passes(number: int) -> None:
    pass


def test_crashes_its_worker() -> None:
    if os.environ.get("CRASH_A_WORKER"):
        os.kill(os.getpid(), signal.SIGSEGV)
"""


def run_suite(folder: Path, crash: bool) -> subprocess.CompletedProcess[str]:
    (folder / "conftest.py").write_text(CONFTEST, encoding="utf-8")
    (folder / "test_small.py").write_text(TESTS, encoding="utf-8")
    environment = {**os.environ, "PYTHONPATH": str(ROOT), "CRASH_A_WORKER": "1" if crash else ""}
    command = [sys.executable, "-m", "pytest", "-n", "2", "-p", "no:cacheprovider", "-q", "--rootdir", str(folder)]
    return subprocess.run([*command, str(folder)], capture_output=True, text=True, env=environment, timeout=300)


@pytest.mark.slow
def test_a_run_whose_workers_finish_ends_and_passes(tmp_path: Path) -> None:
    finished = run_suite(tmp_path, crash=False)
    assert finished.returncode == 0, finished.stdout + finished.stderr
    assert "13 passed" in finished.stdout


@pytest.mark.slow
def test_a_crashed_worker_is_one_named_failure_and_the_rest_still_run(tmp_path: Path) -> None:
    """xdist 3.8's own loadscope ends such a run in an INTERNALERROR that names no test (exit 3)."""
    finished = run_suite(tmp_path, crash=True)
    assert finished.returncode == 1, finished.stdout + finished.stderr
    assert "INTERNALERROR" not in finished.stdout + finished.stderr
    assert "crashed while running 'test_small.py::test_crashes_its_worker'" in finished.stdout
    assert "1 failed, 12 passed" in finished.stdout
