"""Search processes started before their task exists, so that a solve does not wait for one.

Fast Downward's search binary reads its whole task from stdin before it even parses its
options (planner.cc: ``tasks::read_root_task(cin)`` comes first), and it needs the end of
stdin to finish reading. So it can be started ahead of time (process creation, loading the
224 MB binary, dynamic linking, static initialisation: ~3.7 ms of CPU here) and left blocking on
stdin; a solve then writes the task, closes stdin and waits for the plan.

The pool keeps at most one idle process per command (a command fixes the search
configuration). Every started process has its own process group and its own private folder as
working directory, where ``--internal-plan-file`` puts the plan (``fast_downward`` makes it a
FIFO, read as it is written) and its output goes to ``OUTPUT_FILE``. The caller of ``take``
owns the process from then on and ends it with ``retire`` (or ``discard``, on its own thread).
``retire`` does on a background thread what the answer need not wait for: killing the used
process if it still runs (a search that gave its plan is still printing its statistics),
reaping it and removing its folder (~0.6 ms), then starting the replacement. The replacement
starts once the search has ended, not when its predecessor was taken: on two cores its start-up
(~3.7 ms of CPU) would compete with that very search (measured through the app, interleaved:
the search 0.5-1.4 ms faster); now it overlaps the answer going back and the next translation.
A service worker goes one step further and holds its retirements until its answer is sent
(``retirements_held``): cold requests through the app, two servers interleaved, 0.18 and 0.46 ms
faster (p50, two runs).

Forks and exit: a forked child forgets the parent's idle processes and closes its copies of
their stdin (if it kept them, the parent closing stdin would not reach the process as its end
while the child lives); it never waits for or kills them (the pool remembers its owner's pid).
At exit the idle processes are killed, reaped and their folders removed. A process whose owner
dies without cleaning up reads the end of stdin and exits by itself.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import shutil
import signal
import subprocess
import tempfile
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

Command = tuple[str, ...]


@dataclass(frozen=True)
class Started:
    """A process started ahead of its input, the private folder it runs in, and who started it."""

    process: subprocess.Popen[bytes]
    folder: Path
    owner: int  # the pid of the process that started it: only that one may use, kill or reap it


_live: dict[int, Started] = {}
"""Every started process not yet discarded, by pid: a forked child closes its copies of their stdin."""


OUTPUT_FILE = "output"
"""Where a started process's stdout and stderr go: a file in its private folder."""


def start(command: Command) -> Started:
    """Start ``command`` in a new private folder and process group: stdin piped, output to ``OUTPUT_FILE``.

    The output goes to a file, not a pipe: Fast Downward writes its log a line at a time, and a
    reader of a pipe would wake up for each of its ~25 lines while the search runs (measured:
    the search 1.2-1.4 ms slower end to end, on two cores).
    """
    folder = Path(tempfile.mkdtemp(prefix="causalplan-fd-"))
    try:
        output = os.open(folder / OUTPUT_FILE, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        try:
            process = subprocess.Popen(
                command,
                cwd=folder,
                stdin=subprocess.PIPE,
                stdout=output,
                stderr=subprocess.STDOUT,
                start_new_session=True,
                bufsize=0,  # unbuffered: a forked child's copy of stdin holds no data it could flush
            )
        finally:
            os.close(output)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    started = Started(process, folder, os.getpid())
    _live[process.pid] = started
    return started


def discard(started: Started) -> None:
    """Kill ``started``'s process group if it still runs, reap it, and remove its folder.

    Only in the process that started it: a forked child must never touch its parent's.
    """
    if started.owner != os.getpid():
        return
    process = started.process
    if process.poll() is None:  # not reaped yet, so its pid (= group id) cannot have been reused
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGKILL)
    process.communicate()  # closes its stdin and reaps it
    _live.pop(process.pid, None)
    shutil.rmtree(started.folder, ignore_errors=True)


class _Pool:
    """At most one idle started process per command, owned by the process that started them."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._owner = os.getpid()
        self._idle: dict[Command, Started] = {}
        self._starting: dict[Command, threading.Thread] = {}
        self._retiring: set[threading.Thread] = set()
        self._held: list[tuple[Started, Command]] | None = None
        """Retirements put off until ``release`` (None: retirements start at once)."""

    def take(self, command: Command) -> Started:
        """Return a started process for ``command``: the idle one, else a new one (no replacement yet)."""
        ready = self._pop_idle(command)
        if ready is not None and ready.process.poll() is not None:  # it died while idle
            discard(ready)
            ready = None
        return ready or start(command)

    def prestart(self, command: Command) -> None:
        """Start an idle process for ``command`` on a background thread, unless one is there or coming."""
        with self._lock:
            self._check_owner()
            if command in self._idle or command in self._starting:
                return
            thread = threading.Thread(target=self._start_idle, args=(command,), name="causalplan-prestart", daemon=True)
            try:
                thread.start()  # under the lock: ``_pop_idle`` may join it as soon as it is listed
            except RuntimeError:  # the interpreter is shutting down: no new threads
                return
            self._starting[command] = thread

    def retire(self, used: Started, command: Command) -> None:
        """Discard ``used`` on a background thread, then start ``command``'s replacement (see ``prestart``).

        While retirements are held (``hold``), only noted: started by ``release``, or by the next ``take``.
        """
        with self._lock:
            self._check_owner()
            if self._held is not None:
                self._held.append((used, command))
                return
        self._retire_in_background(used, command)

    def hold(self) -> None:
        """Put off retirements until ``release``."""
        with self._lock:
            self._check_owner()
            if self._held is None:
                self._held = []

    def release(self) -> None:
        """Start the retirements put off since ``hold``; later ones start at once again."""
        with self._lock:
            self._check_owner()
            held, self._held = self._held or [], None
        for used, command in held:
            self._retire_in_background(used, command)

    def _start_held(self, command: Command) -> None:
        """Start the held retirements of ``command`` now: a ``take`` needs its replacement."""
        with self._lock:
            if not self._held:
                return
            due = [(used, held) for used, held in self._held if held == command]
            self._held = [(used, held) for used, held in self._held if held != command]
        for used, held in due:
            self._retire_in_background(used, held)

    def _retire_in_background(self, used: Started, command: Command) -> None:
        thread = threading.Thread(target=self._retire, args=(used, command), name="causalplan-retire", daemon=True)
        with self._lock:
            self._check_owner()
            # Listed as the replacement's starter at once (unless one is there or coming), so a
            # ``take`` from now on waits for it rather than starting a process of its own.
            if command not in self._idle and command not in self._starting:
                self._starting[command] = thread
            try:
                thread.start()  # under the lock: ``stop`` joins it as soon as it is listed
            except RuntimeError:  # the interpreter is shutting down: no new threads
                started = False
                if self._starting.get(command) is thread:
                    del self._starting[command]
            else:
                started = True
                self._retiring.add(thread)
        if not started:
            discard(used)

    def idle_pids(self) -> list[int]:
        """Return the pids of this process's idle processes."""
        with self._lock:
            self._check_owner()
            return [started.process.pid for started in self._idle.values()]

    def stop(self) -> None:
        """Wait for processes being started, then kill, reap and remove every idle process."""
        self.release()
        with self._lock:
            self._check_owner()
            starting = [*self._retiring, *self._starting.values()]
        for thread in starting:
            thread.join()
        with self._lock:  # a retirement may have started a replacement
            starting = list(self._starting.values())
        for thread in starting:
            thread.join()
        with self._lock:
            self._check_owner()
            idle, self._idle = list(self._idle.values()), {}
        for started in idle:
            discard(started)

    def forget_after_fork(self) -> None:
        """In a forked child: forget the parent's processes without touching them; close its copies of their stdin."""
        self._lock = threading.Lock()  # the parent's may be held by a thread that does not exist here
        self._forget()

    def _pop_idle(self, command: Command) -> Started | None:
        """Return the idle process for ``command``; wait for the one being started if there is none yet."""
        self._start_held(command)
        with self._lock:
            self._check_owner()
            starting = self._starting.get(command) if command not in self._idle else None
        if starting is not None:  # started earlier, so it is ready sooner than a new one would be
            starting.join()
        with self._lock:
            return self._idle.pop(command, None)

    def _retire(self, used: Started, command: Command) -> None:
        """Discard ``used``, then start ``command``'s replacement on this same thread if it is listed as its starter."""
        this = threading.current_thread()
        try:
            discard(used)
        finally:
            with self._lock:
                self._retiring.discard(this)
                replace = self._starting.get(command) is this
        if replace:
            self._start_idle(command)

    def _start_idle(self, command: Command) -> None:
        started: Started | None = None
        try:
            started = start(command)
        except OSError:  # a missing binary: the solve that needs it reports that
            pass
        finally:
            with self._lock:
                if self._starting.get(command) is threading.current_thread():
                    del self._starting[command]
                keep = started is not None and command not in self._idle
                if started is not None and keep:
                    self._idle[command] = started
        if started is not None and not keep:
            discard(started)

    def _check_owner(self) -> None:
        """Forget the parent's processes in a forked child that the at-fork hook did not see."""
        if os.getpid() != self._owner:
            self._forget()

    def _forget(self) -> None:
        self._idle, self._starting, self._retiring, self._owner = {}, {}, set(), os.getpid()
        self._held = None
        inherited = [started for started in list(_live.values()) if started.owner != self._owner]
        for started in inherited:
            del _live[started.process.pid]
            if started.process.stdin is not None:
                with contextlib.suppress(OSError):
                    started.process.stdin.close()
        # Kept, never discarded: they are the parent's children, so this process must not reap them.
        _inherited.extend(inherited)


_inherited: list[Started] = []


_POOL = _Pool()
os.register_at_fork(after_in_child=_POOL.forget_after_fork)
atexit.register(_POOL.stop)


def take(command: Command) -> Started:
    """Return a started process for ``command``, ready for its input; the caller must ``retire`` it.

    Its replacement is not started here, but by ``retire`` once its search has ended.
    """
    return _POOL.take(command)


def retire(used: Started, command: Command) -> None:
    """After ``used``'s search: discard it and start ``command``'s replacement, on a background thread."""
    _POOL.retire(used, command)


@contextlib.contextmanager
def retirements_held() -> Iterator[None]:
    """Put off ``retire``'s work (killing, reaping, starting the replacement) to the end of the block.

    A service worker holds it while it solves and sends its answer: the retirement's ~0.6 ms of
    Python and the replacement's start-up then no longer compete with the answer for the GIL
    and the two cores. A ``take`` within the block starts its command's held retirement first,
    so a second solve still finds its replacement starting, as it would without the block.
    """
    _POOL.hold()
    try:
        yield
    finally:
        _POOL.release()


def prestart(command: Command) -> None:
    """Start a process for ``command`` in the background now, so the next ``take`` finds it ready."""
    _POOL.prestart(command)


def idle_pids() -> list[int]:
    """Return the pids of the idle started processes."""
    return _POOL.idle_pids()


def stop_idle() -> None:
    """Kill, reap and remove every idle process and its folder (also done at exit)."""
    _POOL.stop()
