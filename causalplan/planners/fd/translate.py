"""FD's translator (PDDL -> SAS), run the way its own entry point runs it, on files in a private folder.

On the main thread it runs in this process: ``options.set_options([...]); main.main()``, with
no Python process to start (most of a translation's time when it runs as its own); an alarm
stops it at the deadline and ``RLIMIT_AS`` bounds its memory. Alarms only reach the main
thread, so elsewhere (a server's threads) it runs as its own process (``python -m
fast_downward.translate``), under the same limits. Both ways get FD's default options and
write ``task.sas`` into the solve's folder.
"""

from __future__ import annotations

import io
import resource
import signal
import sys
import threading
import time
import traceback
from importlib.util import find_spec
from pathlib import Path

from causalplan.planners import processes
from causalplan.planners.fd.returncodes import ExitCode
from causalplan.planners.processes import Finished

DOMAIN_FILE, PROBLEM_FILE, SAS_FILE = "domain.pddl", "problem.pddl", "task.sas"
ALARM_REPEAT_SECONDS = 0.05
"""After the deadline, the in-process translator is interrupted again this often until it stops."""
MIN_TIMER_SECONDS = 0.001
"""An earlier timer that came due during a translation goes off this soon after it."""


def translator_available() -> bool:
    """Return whether FD's translator (the ``fast-downward.translate`` package) is importable."""
    return find_spec("fast_downward.translate") is not None


def translate(domain: str, problem: str, folder: Path, time_limit: float, memory_mb: int) -> Finished:
    """Translate the PDDL texts into ``folder``/task.sas; return how the translator ended."""
    (folder / DOMAIN_FILE).write_text(domain, encoding="utf-8")
    (folder / PROBLEM_FILE).write_text(problem, encoding="utf-8")
    if threading.current_thread() is threading.main_thread():
        return _translate_here(folder, time_limit, memory_mb)
    command = [sys.executable, "-m", "fast_downward.translate", DOMAIN_FILE, PROBLEM_FILE, "--sas-file", SAS_FILE]
    return processes.run_limited(command, folder=folder, time_limit=time_limit, memory_mb=memory_mb)


class _TranslatorTimeout(Exception):
    """Raised by the alarm inside an in-process translation that reached its deadline."""


def _run_main(folder: Path) -> int:
    """Run the translator's ``main`` on the files in ``folder``; return the exit code its ``__main__`` would."""
    from fast_downward.translate import main, options, pddl_parser

    options.set_options([str(folder / DOMAIN_FILE), str(folder / PROBLEM_FILE), "--sas-file", str(folder / SAS_FILE)])
    try:
        main.main()
    except MemoryError:
        return ExitCode.TRANSLATE_OUT_OF_MEMORY
    except pddl_parser.ParseError as exc:
        print(exc)
        return ExitCode.TRANSLATE_INPUT_ERROR
    except SystemExit as exc:  # what its __main__ would exit with: an int, or a message (code 1)
        if isinstance(exc.code, int):
            return exc.code
        print(exc.code)
        return ExitCode.TRANSLATE_CRITICAL_ERROR
    return ExitCode.SUCCESS


WAITING, TRANSLATING, DONE = "waiting", "translating", "done"
"""The in-process translation's stages, as its alarm handler sees them."""


def _translate_here(folder: Path, time_limit: float, memory_mb: int) -> Finished:
    """Translate in this process (main thread only), stopped by an alarm, bounded by ``RLIMIT_AS``.

    A timer the process had set (pytest-timeout's, say) is set again afterwards with what was
    left of it.
    """
    started = time.perf_counter()
    if time_limit <= 0:
        return Finished(None, "", 0.0)
    captured = io.StringIO()
    stage = WAITING

    def on_alarm(signum: int, frame: object) -> None:
        # Armed again before raising: an exception raised inside a garbage-collector callback or
        # under a broad `except` in the translator is lost, and it would run past its deadline.
        # Before the translator starts it only re-arms (the deadline must still reach it); once
        # it has stopped it does nothing: an alarm due then must not break the clean-up below.
        if stage == DONE:
            return
        signal.setitimer(signal.ITIMER_REAL, ALARM_REPEAT_SECONDS)
        if stage == TRANSLATING:
            raise _TranslatorTimeout

    previous_handler = signal.signal(signal.SIGALRM, on_alarm)
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    returncode: int | None = None
    earlier_timer = (0.0, 0.0)
    try:
        resource.setrlimit(resource.RLIMIT_AS, (processes.memory_limit(memory_mb), hard))
        earlier_timer = signal.setitimer(signal.ITIMER_REAL, time_limit)
        stdout, stderr = sys.stdout, sys.stderr
        sys.stdout = sys.stderr = captured
        try:
            stage = TRANSLATING
            returncode = _run_main(folder)
        finally:
            # No call before this line: Python runs signal handlers at calls, so none can raise
            # between the translator's end (or its exception) and here.
            stage = DONE
            sys.stdout, sys.stderr = stdout, stderr
    except _TranslatorTimeout:
        returncode = None
    except Exception:  # noqa: BLE001 - anything else is the translator's critical error, with its traceback
        captured.write(traceback.format_exc())
        returncode = ExitCode.TRANSLATE_CRITICAL_ERROR
    finally:
        stage = DONE  # first, before any call: from here on the handler does nothing
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous_handler)
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
        seconds = time.perf_counter() - started
        if earlier_timer[0] > 0:
            signal.setitimer(signal.ITIMER_REAL, max(earlier_timer[0] - seconds, MIN_TIMER_SECONDS), earlier_timer[1])
    return Finished(returncode, captured.getvalue(), seconds)
