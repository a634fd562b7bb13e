"""Search processes started ahead: used once each, replaced, limited, and never left behind."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from causalplan import caches
from causalplan.objects.catalog import Catalog
from causalplan.pddl.task import build_task
from causalplan.pddl.writer import compile_task
from causalplan.planners import fd
from causalplan.planners.fd import CONFIGS, idle
from causalplan.planners.fd.search import search_command
from causalplan.planners.result import PlanStatus
from tests.conftest import ROOT, example_model
from tests.planners.fd.test_fd import star_task

COMMAND = tuple(search_command(CONFIGS["fd"].search))


@pytest.fixture(autouse=True)
def _no_idle_processes_left() -> Iterator[None]:
    idle.stop()
    yield
    idle.stop()


def _ready() -> idle.Started:
    """Wait until the idle process for the default search is there; return it (still idle)."""
    deadline = time.monotonic() + 30
    while (started := idle._idle.get(COMMAND)) is None:
        assert time.monotonic() < deadline, "the idle process was never started"
        time.sleep(0.005)
    return started


def _desk_lamp(catalog: Catalog) -> tuple[str, str]:
    compiled = compile_task(build_task(example_model("paper/desk_lamp.yaml", catalog), catalog.get("desk_lamp")))
    return compiled.domain, compiled.problem


def test_a_solve_uses_the_idle_process_and_a_replacement_follows(catalog: Catalog) -> None:
    fd.prestart(CONFIGS["fd"])
    first = _ready()
    outcome = fd.solve(*_desk_lamp(catalog), CONFIGS["fd"])
    assert outcome.status is PlanStatus.SOLVED and len(outcome.actions) == 1
    assert first.process.returncode is not None and not first.folder.exists()  # used once, reaped, removed
    second = _ready()
    assert second.process.pid != first.process.pid and second.process.poll() is None


def test_a_process_that_never_asked_starts_none(catalog: Catalog) -> None:
    assert fd.solve(*_desk_lamp(catalog), CONFIGS["fd"]).status is PlanStatus.SOLVED
    time.sleep(0.1)
    assert idle._idle == {} and idle._starting == set()


def test_the_limits_apply_to_a_process_started_ahead() -> None:
    fd.prestart(CONFIGS["fd-opt"])
    compiled = compile_task(star_task(24))
    deadline = time.monotonic() + 30
    while tuple(search_command(CONFIGS["fd-opt"].search)) not in idle._idle:
        assert time.monotonic() < deadline
        time.sleep(0.005)
    assert fd.solve(compiled.domain, compiled.problem, CONFIGS["fd-opt"], time_limit=1.0).status is PlanStatus.TIMEOUT
    caches.current().fd_answers.clear()
    low = fd.solve(compiled.domain, compiled.problem, CONFIGS["fd-opt"], time_limit=60, memory_limit_mb=15)
    assert low.status is PlanStatus.OUT_OF_MEMORY


def test_stop_kills_reaps_and_removes_every_idle_process() -> None:
    fd.prestart(CONFIGS["fd"])
    started = _ready()
    idle.stop()
    assert started.process.returncode is not None and not started.folder.exists()
    assert idle._idle == {}


def test_a_forked_child_leaves_the_parents_idle_process_alone_and_the_parent_still_solves(catalog: Catalog) -> None:
    fd.prestart(CONFIGS["fd"])
    started = _ready()
    pid = os.fork()
    if pid == 0:  # the child: it must forget the process, not kill it
        code = 0 if idle._idle == {} else 1
        idle.stop()
        os._exit(code)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    assert started.process.poll() is None  # still waiting for its task
    assert fd.solve(*_desk_lamp(catalog), CONFIGS["fd"], time_limit=20).status is PlanStatus.SOLVED


def test_idle_processes_and_their_folders_are_gone_when_the_owner_exits(tmp_path: Path) -> None:
    script = (
        "import time\n"
        "from causalplan.planners import fd\n"
        "from causalplan.planners.fd import idle\n"
        "fd.prestart(fd.CONFIGS['fd'])\n"
        "while not idle._idle: time.sleep(0.005)\n"
        "[started] = idle._idle.values()\n"
        "print(started.process.pid, started.folder)\n"
    )
    completed = subprocess.run(
        [sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, check=True, timeout=60
    )
    pid, folder = completed.stdout.split()
    assert not Path(folder).exists()
    assert not Path(f"/proc/{pid}").exists() or "Z" in Path(f"/proc/{pid}/stat").read_text().split()[2]


def test_an_idle_process_that_died_is_not_used_and_is_replaced(catalog: Catalog) -> None:
    fd.prestart(CONFIGS["fd"])
    dead = _ready()
    dead.process.kill()
    dead.process.wait()
    assert fd.solve(*_desk_lamp(catalog), CONFIGS["fd"]).status is PlanStatus.SOLVED  # on a new process
    assert not dead.folder.exists()
    assert _ready().process.poll() is None
