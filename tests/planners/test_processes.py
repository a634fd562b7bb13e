"""Limited runs of external programs: private folder, output, deadline for the whole group, memory."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pytest

from causalplan.planners import processes


def _python(code: str) -> list[str]:
    return [sys.executable, "-c", code]


def test_a_run_gets_its_input_a_private_folder_as_cwd_and_its_output_captured() -> None:
    with processes.private_folder() as folder:
        code = "import os, sys; print(os.getcwd()); print(sys.stdin.read().upper()); sys.exit(3)"
        finished = processes.run_limited(_python(code), folder=folder, time_limit=30, memory_mb=1024, stdin=b"task")
        assert finished.returncode == 3 and not finished.timed_out
        assert finished.output.split() == [str(folder), "TASK"]
    assert not folder.exists()


@pytest.mark.slow
def test_the_deadline_kills_the_whole_process_group(tmp_path: Path) -> None:
    pid_file = tmp_path / "grandchild"
    code = (
        "import subprocess, time; child = subprocess.Popen(['sleep', '60']); "
        f"open({str(pid_file)!r}, 'w').write(str(child.pid)); time.sleep(60)"
    )
    started = time.monotonic()
    finished = processes.run_limited(_python(code), folder=tmp_path, time_limit=1.0, memory_mb=1024)
    assert finished.timed_out and finished.returncode is None
    assert time.monotonic() - started < 20
    grandchild = int(pid_file.read_text())
    deadline = time.monotonic() + 10  # killed with its group; reaped by init soon after
    while Path(f"/proc/{grandchild}").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not Path(f"/proc/{grandchild}").exists()


def test_the_memory_limit_stops_a_program_that_allocates_more(tmp_path: Path) -> None:
    code = "import sys\ntry:\n    b = bytearray(400 * 1024 * 1024)\nexcept MemoryError:\n    sys.exit(7)"
    finished = processes.run_limited(_python(code), folder=tmp_path, time_limit=30, memory_mb=200)
    assert finished.returncode == 7
    assert processes.run_limited(_python(code), folder=tmp_path, time_limit=30, memory_mb=2048).returncode == 0


def test_no_time_left_runs_nothing(tmp_path: Path) -> None:
    finished = processes.run_limited(_python("open('ran', 'w')"), folder=tmp_path, time_limit=0, memory_mb=1024)
    assert finished.timed_out and not (tmp_path / "ran").exists()


def test_a_memory_limit_above_the_parents_hard_limit_is_lowered_to_it() -> None:
    import resource

    _soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    expected = 64 * 1024 * 1024 if hard == resource.RLIM_INFINITY else min(64 * 1024 * 1024, hard)
    assert processes.memory_limit(64) == expected
