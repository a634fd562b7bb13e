"""One planner worker process as the app sees it: started, called, stopped or killed, and its temp folder.

A worker is a fresh interpreter (``python -c 'from causalplan.service.pool.worker import main;
main()'``), not a fork of the app (which runs uvicorn's and anyio's threads), in a process
group of its own, talking to the app over a private socket pair.

Each worker gets a temp folder of its own (its TMPDIR), made and removed here, by the app: a
killed worker cannot clean up after itself. The folder's name holds the app's pid, so an app
that was itself killed leaves folders the next app recognises as stale and removes
(``remove_stale_folders``).
"""

from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
from contextlib import suppress
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

from causalplan.planners import processes

STOP_SECONDS = 2.0
FOLDER_PREFIX = "causalplan-worker-"
_FOLDER_NAME = re.compile(re.escape(FOLDER_PREFIX) + r"(\d+)-")
_WORKER_MAIN = "from causalplan.service.pool.worker import main; main()"


def _is_running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: running
        return True
    return True


def remove_stale_folders(root: Path | None = None) -> list[Path]:
    """Remove the worker temp folders of apps that no longer run (killed before they could); return them."""
    root = root or Path(tempfile.gettempdir())
    removed: list[Path] = []
    with suppress(OSError):
        for folder in root.glob(FOLDER_PREFIX + "*"):
            match = _FOLDER_NAME.match(folder.name)
            if match is None or not folder.is_dir() or _is_running(int(match.group(1))):
                continue
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
    return removed


class WorkerProcess:
    """A started worker; ``kill`` and ``stop``, which every way of ending one goes through, remove its folder."""

    def __init__(self, memory_mb: int, quiet: bool = False) -> None:
        self.temp_folder = Path(tempfile.mkdtemp(prefix=f"{FOLDER_PREFIX}{os.getpid()}-"))
        self._folder_lock = threading.Lock()
        self._folder_removed = False
        parent_end, child_end = socket.socketpair()
        # Jobs are pickled by reference (module and name), so a worker must import what the app
        # can: it gets the app's import path. TMPDIR: ``tempfile`` (and FD's processes, which
        # inherit it) put their folders in the worker's own.
        environment = {
            **os.environ,
            "PYTHONPATH": os.pathsep.join(path for path in sys.path if path),
            "TMPDIR": str(self.temp_folder),
        }
        try:
            with child_end:
                self.process = subprocess.Popen(
                    [sys.executable, "-c", _WORKER_MAIN, str(child_end.fileno()), str(memory_mb)],
                    pass_fds=[child_end.fileno()],
                    stdin=subprocess.DEVNULL,
                    stdout=subprocess.DEVNULL,  # C extensions print banners; errors still reach stderr
                    stderr=subprocess.DEVNULL if quiet else None,
                    process_group=0,
                    env=environment,
                )
        except BaseException:  # no worker, so no ``kill`` or ``stop`` will come to clean up
            parent_end.close()
            self._remove_folder()
            raise
        self.connection = Connection(parent_end.detach())
        self.is_ready = False

    @property
    def pid(self) -> int:
        return self.process.pid

    def is_alive(self) -> bool:
        return self.process.poll() is None

    def wait_ready(self, timeout: float) -> None:
        """Wait for the worker's hello (sent once it has imported the planners); TimeoutError, EOFError."""
        if self.is_ready:
            return
        if not self.connection.poll(timeout):
            raise TimeoutError
        self.connection.recv()
        self.is_ready = True

    def receive(self, timeout: float) -> Any:
        """Return the worker's next message; TimeoutError when none comes in time, EOFError when it died."""
        if not self.connection.poll(max(0.0, timeout)):
            raise TimeoutError
        return self.connection.recv()

    def exit_code(self) -> int | None:
        """Return the exit code of a worker that has stopped (None if it is still running)."""
        try:
            return self.process.wait(STOP_SECONDS)
        except subprocess.TimeoutExpired:
            return None

    def kill(self) -> None:
        """Kill the worker and what it started (its process group, and children in sessions of their own).

        Safe to call more than once, and from two threads at once (a closing pool and the request
        that timed out may both kill a busy worker).
        """
        try:
            processes.kill_group(self.process)
            self.connection.close()
        finally:
            self._remove_folder()

    def stop(self) -> None:
        """Ask the worker to finish, and kill it if it does not."""
        with suppress(BrokenPipeError, OSError):
            self.connection.send(None)
        try:
            self.process.wait(STOP_SECONDS)
        except subprocess.TimeoutExpired:
            self.kill()
            return
        try:
            self.connection.close()
        finally:
            self._remove_folder()

    def _remove_folder(self) -> None:
        with self._folder_lock:
            if self._folder_removed:
                return
            self._folder_removed = True
        shutil.rmtree(self.temp_folder, ignore_errors=True)
