"""Search processes started before their task, for a process that solves again and again (a service worker).

FD's search binary reads its whole task from stdin before anything else, so it can be started
ahead (process creation, loading and linking the binary) and left waiting on stdin. Only a
process that calls ``prestart`` gets one: a one-shot ``causalplan plan`` never does. There
is at most one idle process per search command; a solve takes it, and once that search has
ended a replacement is started on a background thread (so it does not compete with the search
for the CPU). Each process has a private folder as its working directory (where its plan is
written), removed when the process is done with. A forked child forgets its parent's idle
processes and closes its copies of their stdin (else FD would never see the end of its task).

Not a worker manager, so not the service pool's ``pebble``: pebble runs Python functions in
Python workers, and has no way to keep a program started ahead, waiting for its input.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import shutil
import subprocess
import tempfile
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from causalplan.planners import processes

Command = tuple[str, ...]


@dataclass(frozen=True)
class Started:
    """A search process waiting for its task, and the private folder it runs in."""

    process: subprocess.Popen[bytes]
    folder: Path


_lock = threading.Lock()
_idle: dict[Command, Started] = {}
_prestarted: set[Command] = set()
"""The commands this process asked to have ready: only they get replacements."""
_owner = [os.getpid()]
_starting: set[threading.Thread] = set()
"""Threads starting a replacement now: ``stop`` waits for them, so none is left behind at exit."""


def _start(command: Command) -> Started:
    folder = Path(tempfile.mkdtemp(prefix="causalplan-fd-"))
    try:
        return Started(processes.start(command, folder=folder), folder)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise


def discard(started: Started) -> None:
    """Kill ``started``'s group if it still runs, reap it and remove its folder."""
    processes.kill_group(started.process)
    if started.process.stdin is not None:
        started.process.stdin.close()
    shutil.rmtree(started.folder, ignore_errors=True)


def _start_idle(command: Command) -> None:
    started: Started | None = None
    with contextlib.suppress(OSError):  # a missing binary: the solve that needs it reports that
        started = _start(command)
    with _lock:
        _starting.discard(threading.current_thread())
        keep = started is not None and command in _prestarted and command not in _idle and _owner[0] == os.getpid()
        if keep and started is not None:
            _idle[command] = started
    if started is not None and not keep:
        discard(started)


def _start_in_background(command: Command) -> None:
    thread = threading.Thread(target=_start_idle, args=(command,), name="causalplan-prestart", daemon=True)
    with _lock:
        _starting.add(thread)
        try:
            thread.start()
        except RuntimeError:  # the interpreter is shutting down: no new threads
            _starting.discard(thread)


def prestart(command: Sequence[str]) -> None:
    """Have a process for ``command`` ready from now on: start one in the background, and replace it after use."""
    key = tuple(command)
    with _lock:
        _prestarted.add(key)
        ready = key in _idle
    if not ready:
        _start_in_background(key)


def take(command: Sequence[str]) -> Started | None:
    """Return the idle process for ``command`` (the caller owns it now), or None if there is none."""
    with _lock:
        started = _idle.pop(tuple(command), None)
    if started is not None and started.process.poll() is not None:  # it died while idle
        discard(started)
        return None
    return started


def replace_used(command: Sequence[str]) -> None:
    """After a search for ``command``: start its replacement in the background, if it is prestarted."""
    key = tuple(command)
    with _lock:
        wanted = key in _prestarted and key not in _idle
    if wanted:
        _start_in_background(key)


def stop() -> None:
    """Kill, reap and remove every idle process (also done at exit); nothing is started again."""
    with _lock:
        _prestarted.clear()  # a replacement being started now is discarded by its thread
        starting = list(_starting)
    for thread in starting:
        thread.join()
    with _lock:
        idle = list(_idle.values()) if _owner[0] == os.getpid() else []
        _idle.clear()
    for started in idle:
        discard(started)


def _forget_after_fork() -> None:
    """In a forked child: the idle processes are the parent's; close this copy of their stdin, never reap them."""
    global _lock
    _lock = threading.Lock()  # the parent's may be held by a thread that does not exist here
    for started in _idle.values():
        if started.process.stdin is not None:
            with contextlib.suppress(OSError):
                started.process.stdin.close()  # this process's copy only
    _idle.clear()
    _prestarted.clear()
    _starting.clear()
    _owner[0] = os.getpid()


os.register_at_fork(after_in_child=_forget_after_fork)
atexit.register(stop)
