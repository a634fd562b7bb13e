"""External programs run with limits: the one module that starts them (FD, VAL, comparison runs).

Each run gets a private temp folder as its working directory (FD's search writes its plan
there, so concurrent runs never share files), its own process group (killed whole at the
deadline), an address-space limit (``RLIMIT_AS``) and its output captured in ``OUTPUT_FILE``
there (a file, not a pipe: a reader of a pipe wakes for every line a program logs); the
command is logged shell-quoted. A service worker stopped by its pool takes the programs it
started with it (``kill_children``).
"""

from __future__ import annotations

import contextlib
import logging
import os
import resource
import shlex
import signal
import subprocess
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

logger = logging.getLogger(__name__)

OUTPUT_FILE = "output.log"
"""Where a run's stdout and stderr go, in its folder."""


@dataclass(frozen=True)
class Finished:
    """How a limited run ended: its exit code (None: killed at the deadline), its output, its wall time."""

    returncode: int | None
    output: str
    seconds: float

    @property
    def timed_out(self) -> bool:
        return self.returncode is None


@contextlib.contextmanager
def private_folder(prefix: str = "causalplan-") -> Iterator[Path]:
    """Yield a new temp folder only this run uses; it is removed with everything in it afterwards."""
    with tempfile.TemporaryDirectory(prefix=prefix) as folder:
        yield Path(folder)


def memory_limit(megabytes: int) -> int:
    """Return ``megabytes`` in bytes, lowered to this process's hard ``RLIMIT_AS`` if it has one.

    A child cannot be given more than its parent's hard limit, and trying is an error.
    """
    _soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = megabytes * 1024 * 1024
    return limit if hard == resource.RLIM_INFINITY else min(limit, hard)


def limit_memory(pid: int, megabytes: int) -> None:
    """Set the address-space limit of process ``pid`` (a child just started) to ``megabytes``."""
    limit = memory_limit(megabytes)
    with contextlib.suppress(ProcessLookupError):  # it has already finished
        resource.prlimit(pid, resource.RLIMIT_AS, (limit, limit))


def children_of(pid: int) -> list[int]:
    """Return the pids of the children of process ``pid`` (empty when /proc does not list them)."""
    children: list[int] = []
    with contextlib.suppress(OSError):
        for task in Path(f"/proc/{pid}/task").iterdir():
            with contextlib.suppress(OSError, ValueError):
                children.extend(int(child) for child in (task / "children").read_text().split())
    return children


def kill_children(pid: int) -> None:
    """Kill the children of process ``pid`` and the process groups they lead (FD's runs lead their own)."""
    for child in children_of(pid):
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(child, signal.SIGKILL)
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(child, signal.SIGKILL)  # a child that leads no group of its own


def kill_group(process: subprocess.Popen[bytes]) -> None:
    """Kill ``process``, everything it started (its process group), and the groups its children lead, then reap it.

    The one place a started program is killed (FD's runs, the idle searches); a service worker
    that its pool stops calls ``kill_children`` on itself.
    """
    if process.returncode is None:  # not reaped yet, so its pid (= its group id) cannot have been reused
        kill_children(process.pid)  # found before it dies, killed with it
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(process.pid, signal.SIGKILL)
    process.wait()


def start(command: Sequence[str], *, folder: Path) -> subprocess.Popen[bytes]:
    """Start ``command`` in ``folder`` and a process group of its own, stdin piped, output to ``OUTPUT_FILE``."""
    logger.debug("running (cwd %s): %s", folder, shlex.join(command))
    with (folder / OUTPUT_FILE).open("wb") as output:
        return subprocess.Popen(
            command, cwd=folder, stdin=subprocess.PIPE, stdout=output, stderr=subprocess.STDOUT, start_new_session=True
        )


def output_in(folder: Path) -> str:
    """Return the output a run left in ``folder`` (its ``OUTPUT_FILE``), empty when there is none."""
    try:
        return (folder / OUTPUT_FILE).read_text(encoding="utf-8", errors="replace")
    except FileNotFoundError:
        return ""


def finish(
    process: subprocess.Popen[bytes], *, folder: Path, time_limit: float, memory_mb: int, stdin: bytes = b""
) -> Finished:
    """Limit a started process's memory, give it ``stdin``, and wait for its end; kill its group at ``time_limit``.

    The memory limit is set now rather than by a ``preexec_fn``, which would make Python fork
    instead of vfork; the programs run here read their input before they allocate much.
    """
    started = time.perf_counter()
    limit_memory(process.pid, memory_mb)
    try:
        process.communicate(stdin, timeout=max(time_limit, 0.001))
    except subprocess.TimeoutExpired:
        kill_group(process)
        process.communicate()
        return Finished(None, output_in(folder), time.perf_counter() - started)
    except BaseException:
        kill_group(process)
        raise
    return Finished(process.returncode, output_in(folder), time.perf_counter() - started)


def run_limited(
    command: Sequence[str],
    *,
    folder: Path,
    time_limit: float,
    memory_mb: int,
    stdin: bytes = b"",
) -> Finished:
    """Run ``command`` in ``folder`` with ``stdin`` as its input; kill its group at ``time_limit`` seconds."""
    if time_limit <= 0:
        return Finished(None, "", 0.0)
    started = time.perf_counter()
    process = start(command, folder=folder)
    finished = finish(process, folder=folder, time_limit=time_limit, memory_mb=memory_mb, stdin=stdin)
    return Finished(finished.returncode, finished.output, time.perf_counter() - started)
