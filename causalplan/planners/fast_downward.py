"""Fast Downward, run directly on our PDDL: the one module that runs it (``search_processes`` starts it).

The translator is FD's Python package, run on the PDDL texts in memory: on the main thread in
this process (no start-up at all; an alarm stops it at the deadline, RLIMIT_AS bounds its
memory), on other threads in a forked copy of this process that is killed at the deadline.
The SAS task it produces goes to the search binary's stdin: a process started ahead of time
(``search_processes``; ``CAUSALPLAN_SEARCH_PRESTART=0`` starts one per search instead), in its
own process group and private folder, memory-limited when it gets its task and killed at the
deadline. Its plan is read from a FIFO as FD writes it, and taken once complete, before FD
exits. Exit codes map to ``PlanStatus`` in one place.
"""

from __future__ import annotations

import contextlib
import gc
import io
import logging
import math
import os
import re
import resource
import select
import shlex
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache
from importlib.util import find_spec
from pathlib import Path
from typing import Any

from causalplan.errors import PlannerUnavailableError
from causalplan.planners import canonical_translation, search_processes
from causalplan.planners.result import PlanStatus, SearchOutcome

logger = logging.getLogger(__name__)

DEFAULT_TIME_LIMIT = 30.0
DEFAULT_MEMORY_LIMIT_MB = 2048

# Silent: FD's log is only read for the tail of an error, and errors are printed regardless;
# writing the rest through a pipe cost ~0.5 ms of a ~5 ms search on the paper's objects.
LAMA_FIRST = (
    "let(hlm, eval_modify_costs(landmark_sum(lm_factory=lm_reasonable_orders_hps(lm_rhw(verbosity=silent),"
    "verbosity=silent),pref=false,verbosity=silent),cost_type=one),"
    "let(hff, eval_modify_costs(ff(verbosity=silent),cost_type=one),"
    "lazy_greedy([hff,hlm],preferred=[hff,hlm],cost_type=one,reopen_closed=false,verbosity=silent)))"
)
OPTIMAL = "astar(hmax(verbosity=silent),verbosity=silent)"
"""A* with h^max: admissible with derived predicates (ours never occur negated)."""
COMPLETE = "astar(blind(verbosity=silent),verbosity=silent)"
"""Blind A*: complete, so exhausting it proves that no plan exists."""


@dataclass(frozen=True)
class SearchConfig:
    """One way of running FD's search: its ``--search`` string, and whether plans are shortest."""

    name: str
    search: str
    optimal: bool
    description: str


CONFIGS: dict[str, SearchConfig] = {
    "fd": SearchConfig("fd", LAMA_FIRST, False, "Fast Downward, LAMA's first iteration (fast, not shortest)"),
    "fd-opt": SearchConfig("fd-opt", OPTIMAL, True, "Fast Downward, A* with h^max (shortest plans)"),
}

# Fast Downward's exit codes (driver/returncodes.py) and what they mean for us.
_EXIT_STATUS: dict[int, PlanStatus] = {
    0: PlanStatus.SOLVED,
    1: PlanStatus.SOLVED,  # plan found, then out of memory
    2: PlanStatus.SOLVED,  # plan found, then out of time
    3: PlanStatus.SOLVED,
    10: PlanStatus.UNSOLVABLE,  # translator proved it
    11: PlanStatus.UNSOLVABLE,  # complete search proved it
    20: PlanStatus.OUT_OF_MEMORY,
    21: PlanStatus.TIMEOUT,
    22: PlanStatus.OUT_OF_MEMORY,
    23: PlanStatus.TIMEOUT,
    24: PlanStatus.OUT_OF_MEMORY,
}
INCOMPLETE_EXIT = 12


def status_of_exit_code(code: int) -> PlanStatus:
    """Return the status an FD exit code stands for (anything unknown is an error)."""
    if code < 0:  # killed by a signal; SIGKILL comes from our own limits
        return PlanStatus.OUT_OF_MEMORY if code == -signal.SIGSEGV else PlanStatus.ERROR
    return _EXIT_STATUS.get(code, PlanStatus.ERROR)


@cache
def search_binary() -> Path:
    """Return the path of FD's search binary (``CAUSALPLAN_FD_BINARY`` overrides the wheel's)."""
    override = os.environ.get("CAUSALPLAN_FD_BINARY")
    if override:
        path = Path(override)
    else:
        spec = find_spec("up_fast_downward")
        if spec is None or not spec.submodule_search_locations:
            raise PlannerUnavailableError("Fast Downward is not installed: pip install up-fast-downward")
        path = Path(next(iter(spec.submodule_search_locations))) / "downward/builds/release/bin/downward"
    if not os.access(path, os.X_OK):
        raise PlannerUnavailableError(f"Fast Downward's search binary is missing or not executable: {path}")
    return path


def translator_available() -> bool:
    """Return whether FD's translator (the ``fast-downward.translate`` package) is importable."""
    return find_spec("fast_downward.translate") is not None


def _memory_limit(memory_mb: int) -> int:
    """Return ``memory_mb`` in bytes, lowered to this process's hard RLIMIT_AS if it has one.

    A parent's limit (e.g. a comparison worker's) cannot be raised, and trying is an error.
    """
    _soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = memory_mb * 1024 * 1024
    return limit if hard == resource.RLIM_INFINITY else min(limit, hard)


def _limit_process(pid: int, memory_mb: int) -> None:
    limit = _memory_limit(memory_mb)
    with contextlib.suppress(ProcessLookupError):  # it has already finished
        resource.prlimit(pid, resource.RLIMIT_AS, (limit, limit))


@dataclass(frozen=True)
class _Run:
    returncode: int | None  # None: killed at the time limit
    seconds: float
    output: str
    product: str | None = None  # the translator's SAS task, the search's plan


PLAN_FILE = "plan"
"""Where the search writes its plan: a FIFO in its process's private folder, read as it is written."""
PLAN_END = re.compile(rb"^; cost = \d+ \((unit|general) cost\)\n\Z", re.MULTILINE)
"""The line FD ends a plan file with; a plan without it is incomplete."""
_PLAN_CHUNK = 65536


def _search_command(binary: Path, search: str) -> search_processes.Command:
    return (str(binary), "--search", search, "--internal-plan-file", PLAN_FILE)


def _prestart_enabled() -> bool:
    """Return whether searches use processes started ahead (``CAUSALPLAN_SEARCH_PRESTART=0``: no)."""
    return os.environ.get("CAUSALPLAN_SEARCH_PRESTART", "1") != "0"


def _search(command: search_processes.Command, sas: bytes, deadline: float, memory_mb: int) -> _Run:
    """Run one search on ``sas`` in a started search process; return its exit code, output and plan."""
    began = time.perf_counter()
    prestarted = _prestart_enabled()
    search = search_processes.take(command) if prestarted else search_processes.start(command)
    try:
        handed = _hand_over(search, command, sas, deadline, memory_mb)
    finally:
        # Cleaned up and replaced off this thread, now that the search is over; a search that
        # gave its plan and is still printing its statistics is killed there.
        if prestarted:
            search_processes.retire(search, command)
        else:
            search_processes.discard(search)
    plan = handed.plan.decode("utf-8") if handed.plan is not None else None
    return _Run(handed.returncode, time.perf_counter() - began, handed.output.decode("utf-8", "replace"), plan)


@dataclass(frozen=True)
class _Handed:
    """What came back of one search: exit code (None: killed at the deadline), output, complete plan."""

    returncode: int | None
    output: bytes
    plan: bytes | None


def _hand_over(
    search: search_processes.Started, command: search_processes.Command, sas: bytes, deadline: float, memory_mb: int
) -> _Handed:
    """Write the task to the search's stdin, and read its plan as it writes it; kill its group at ``deadline``.

    The plan file is a FIFO made here: FD opens it, writes the plan and closes it once it has
    found one, and a complete plan (its last line ``; cost = ...``) is the answer at once,
    without waiting for FD to print its statistics and exit (~1.3 ms of a ~5 ms search here).
    Its exit code is then 0 (what FD exits with after a plan). Without a complete plan, the
    process's own end gives the exit code. Its output is read from its file at the end:
    nothing wakes this thread while the search runs but the plan.
    """
    logger.debug("searching (cwd %s): %s", search.folder, shlex.join(command))
    process = search.process
    # Limited now, for this solve, rather than when started: each solve may have its own limit,
    # and a preexec_fn would stop Python from using vfork (~10 ms more from a large process).
    _limit_process(process.pid, memory_mb)
    os.mkfifo(search.folder / PLAN_FILE, 0o600)  # FD opens it only once it has a plan
    plan_reader = os.open(search.folder / PLAN_FILE, os.O_RDONLY | os.O_NONBLOCK)
    pidfd = os.pidfd_open(process.pid)  # readable once the process has ended
    try:
        outcome, plan = _follow(process, pidfd, plan_reader, sas, deadline)
    finally:
        os.close(pidfd)
        os.close(plan_reader)
    returncode: int | None
    if outcome == "plan":
        returncode = 0
    elif outcome == "ended":
        returncode = process.wait()
    else:  # the deadline
        with contextlib.suppress(ProcessLookupError):  # not reaped yet, so the group is still its own
            os.killpg(process.pid, signal.SIGKILL)
        process.wait()
        returncode = None
    try:
        output = (search.folder / search_processes.OUTPUT_FILE).read_bytes()
    except FileNotFoundError:
        output = b""
    return _Handed(returncode, output, plan)


def _follow(
    process: subprocess.Popen[bytes], pidfd: int, plan_reader: int, sas: bytes, deadline: float
) -> tuple[str, bytes | None]:
    """Write ``sas`` to the process's stdin and read the FIFO ``plan_reader`` until an outcome.

    Returns ``("plan", plan)`` once the plan's writer has closed it complete, ``("ended", the
    complete plan or None)`` when the process has ended first, or ``("deadline", None)``. The task is written
    as the process reads it (most fit in the pipe's buffer: one write); a process that ends
    before reading it all (a task it rejects) stops the writing. poll, not select: a server may
    have more than 1024 open files.
    """
    stdin = process.stdin
    assert stdin is not None  # started with stdin piped
    descriptor = stdin.fileno()
    os.set_blocking(descriptor, False)
    writing: int | None = descriptor  # None once the whole task is written
    rest = memoryview(sas)
    plan = bytearray()
    poller = select.poll()
    poller.register(pidfd, select.POLLIN)
    poller.register(plan_reader, select.POLLIN)
    poller.register(descriptor, select.POLLOUT)
    try:
        while True:
            if writing is not None:
                try:
                    rest = rest[os.write(writing, rest) :]
                except BlockingIOError:  # the pipe is full: wait until it is not
                    pass
                except BrokenPipeError:  # it ended before reading the whole task
                    rest = rest[len(rest) :]
                if not rest:
                    poller.unregister(writing)
                    stdin.close()
                    writing = None
            remaining = deadline - time.monotonic()
            events = dict(poller.poll(max(0, math.ceil(remaining * 1000)))) if remaining > 0 else {}
            if not events:  # also when events kept coming past the deadline (a plan written forever)
                return "deadline", None
            if plan_reader in events:
                plan += _read_available(plan_reader)
                if events[plan_reader] & select.POLLHUP:  # its writer closed it: all it wrote is read
                    if PLAN_END.search(plan):
                        return "plan", bytes(plan)
                    poller.unregister(plan_reader)  # incomplete: the exit code says why
            if pidfd in events:
                with contextlib.suppress(OSError):
                    plan += _read_available(plan_reader)
                return "ended", bytes(plan) if PLAN_END.search(plan) else None
    finally:
        if not stdin.closed:
            stdin.close()


def _read_available(descriptor: int) -> bytes:
    """Return what can be read from the non-blocking ``descriptor`` now (b"" at its end)."""
    chunks = []
    while True:
        try:
            chunk = os.read(descriptor, _PLAN_CHUNK)
        except BlockingIOError:
            break
        if not chunk:
            break
        chunks.append(chunk)
    return b"".join(chunks)


def _wait_for(pidfd: int, deadline: float) -> bool:
    """Return whether the process behind ``pidfd`` ends before ``deadline`` (poll: any descriptor number)."""
    poller = select.poll()
    poller.register(pidfd, select.POLLIN)
    return bool(poller.poll(max(0, math.ceil((deadline - time.monotonic()) * 1000))))


TRANSLATE_OUT_OF_MEMORY = 20
TRANSLATE_CRITICAL_ERROR = 30
TRANSLATE_INPUT_ERROR = 31


TRANSLATOR_ARGUMENTS = ("--invariant-generation-max-candidates", "0")
"""The translator's options beyond its defaults: no invariant synthesis.

Measured interleaved: ~7% of one example's translation, ~3% over the paper's four objects.

Invariants group facts into multi-valued variables, and in causalplan's domains no group can
hold two facts: ``in-assembly`` is only ever added and ``available`` only ever deleted, so every
variable is binary either way. Tests check that the SAS task is byte-identical to the one with
the translator's defaults on every example and on synthetic tasks, in both PDDL forms.
"""


@cache
def translator_options() -> Any:
    """Return the translator's options (file names are never read, so any will do)."""
    from fast_downward.translate import options

    return options.parse_args(["domain.pddl", "problem.pddl", *TRANSLATOR_ARGUMENTS])


_shortcut_lock = threading.Lock()


def install_invariant_shortcut() -> None:
    """Let FD's invariant search end at once when it may take no candidate (once per process).

    With ``--invariant-generation-max-candidates 0`` (``TRANSLATOR_ARGUMENTS``), FD's
    ``find_invariants`` takes no candidate and so finds no invariant, but first builds its
    ``BalanceChecker``: a copy of every action with inequality preconditions, ~0.24 ms of a
    paper task's 1.5-1.75 ms translation (interleaved in one process). With that limit, this
    prints what FD prints and finds nothing; with any other, FD's own function runs. Tests check
    the SAS task byte for byte against the translator's own process.
    """
    from fast_downward.translate import invariant_finder, options

    if getattr(invariant_finder.find_invariants, "is_causalplan_shortcut", False):
        return  # every translation after the first: no lock to take
    with _shortcut_lock:
        original: Callable[[Any, Any], Any] = invariant_finder.find_invariants
        if getattr(original, "is_causalplan_shortcut", False):
            return

        def find_invariants(task: Any, reachable_action_params: Any) -> Any:
            if options.get_options().invariant_generation_max_candidates == 0:
                print(0, "initial candidates")
                return iter(())
            return original(task, reachable_action_params)

        find_invariants.is_causalplan_shortcut = True  # type: ignore[attr-defined]
        invariant_finder.find_invariants = find_invariants


def parse_pddl(kind: str, text: str) -> Any:
    """Return the nested lists of a PDDL text, as the translator's ``parse_pddl_file`` does for a file."""
    from fast_downward.translate.pddl_parser import ParseError, lisp_parser

    try:
        return lisp_parser.parse_nested_list(io.StringIO(text, newline=None))  # lines split as open() does
    except ParseError as exc:
        raise ParseError(f"Error: Could not parse {kind} file: {kind}.pddl\nReason: {exc}") from exc


def _run_translator(domain: str, problem: str) -> tuple[int, str | None]:
    """Run FD's translator on the PDDL texts in this process; return its exit code and the SAS task.

    The steps of the translator's ``main.main()`` on texts in memory: no files to write and read
    back, no argument parsing per run (the options never change), and no statistics (only printed).
    A task in the canonical form takes ``canonical_translation``'s shorter way to the same result.
    Tests check that its SAS task is byte-identical to the translator's own, run as a process.
    """
    from fast_downward.translate import main, normalize, options, pddl_parser
    from fast_downward.translate.pddl_parser import parsing_functions

    options.options = translator_options()  # set on every run: it is the translator's global
    install_invariant_shortcut()
    try:
        sas_task = canonical_translation.sas_task(domain, problem)
        if sas_task is None:
            task = parsing_functions.parse_task(parse_pddl("domain", domain), parse_pddl("problem", problem))
            normalize.normalize(task)
            sas_task = main.pddl_to_sas(task)
        sas = io.StringIO()
        sas_task.output(sas)
    except MemoryError:
        return TRANSLATE_OUT_OF_MEMORY, None
    except pddl_parser.ParseError as exc:
        print(exc)
        return TRANSLATE_INPUT_ERROR, None
    except SystemExit as exc:
        return (exc.code if isinstance(exc.code, int) else TRANSLATE_CRITICAL_ERROR), None
    return 0, sas.getvalue()


def _translate_in_child(domain: str, problem: str, work: Path, memory_mb: int) -> None:
    """Translate in this (forked) process into ``work``/task.sas; exit with the translator's code."""
    log = os.open(work / "translate.log", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    os.dup2(log, 1)
    os.dup2(log, 2)
    code = TRANSLATE_CRITICAL_ERROR
    try:
        limit = _memory_limit(memory_mb)
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        code, sas = _run_translator(domain, problem)
        if sas is not None:
            (work / "task.sas").write_text(sas, encoding="utf-8")
    except BaseException:  # noqa: BLE001 - anything else is the translator's critical error
        import traceback

        traceback.print_exc()
        code = TRANSLATE_CRITICAL_ERROR
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


class _TranslatorTimeout(Exception):
    """Raised by the alarm inside an in-process translation that reached its deadline."""


ALARM_REPEAT_SECONDS = 0.05
"""After the deadline, the in-process translator is interrupted again this often until it stops."""


def _translate_here(domain: str, problem: str, deadline: float, memory_mb: int) -> _Run:
    """Translate in this process (main thread only): no fork, no start-up; limits by alarm and rlimit.

    FD's translator keeps module state between runs, but rebuilds all of it from the options
    and texts of each run (tests check that its output is byte-identical to a fresh process's).
    """
    started = time.perf_counter()
    remaining = deadline - time.monotonic()
    if remaining <= 0:
        return _Run(None, 0.0, "")
    captured = io.StringIO()

    def on_alarm(signum: int, frame: object) -> None:
        # Armed again before raising: an exception raised inside a garbage-collector callback
        # (libraries such as Hypothesis install them) or under a broad `except` in the
        # translator is lost, and the translation would run on past its deadline.
        signal.setitimer(signal.ITIMER_REAL, ALARM_REPEAT_SECONDS)
        raise _TranslatorTimeout

    previous_handler = signal.signal(signal.SIGALRM, on_alarm)
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = _memory_limit(memory_mb)
    returncode: int | None
    sas: str | None = None
    try:
        resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
        signal.setitimer(signal.ITIMER_REAL, remaining)
        with contextlib.redirect_stdout(captured), contextlib.redirect_stderr(captured):
            returncode, sas = _run_translator(domain, problem)
    except _TranslatorTimeout:
        returncode = None
    except Exception:  # noqa: BLE001 - anything else is the translator's critical error
        import traceback

        captured.write(traceback.format_exc())
        returncode = TRANSLATE_CRITICAL_ERROR
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous_handler)
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
    return _Run(returncode, time.perf_counter() - started, captured.getvalue(), sas)


def _translator_in_process() -> bool:
    """Return whether to translate in this process: only on the main thread (alarms need it)."""
    if os.environ.get("CAUSALPLAN_TRANSLATOR", "in-process") == "fork":
        return False
    return threading.current_thread() is threading.main_thread()


def _wait(pid: int, deadline: float) -> int | None:
    """Wait for child ``pid`` until ``deadline``; return its exit code, or None after killing it."""
    pidfd = os.pidfd_open(pid)
    try:
        ready = _wait_for(pidfd, deadline)
    finally:
        os.close(pidfd)
    if not ready:
        os.kill(pid, signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status) if ready else None


def _translate(domain: str, problem: str, deadline: float, memory_mb: int) -> _Run:
    """Run the translator on the PDDL texts; its ``product`` is the SAS task."""
    import fast_downward.translate.main  # noqa: F401 - imported once here, so the fork has it

    if _translator_in_process():
        return _translate_here(domain, problem, deadline, memory_mb)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="causalplan-translate-") as folder:
        work = Path(folder)
        sys.stdout.flush()
        sys.stderr.flush()
        # Freezing moves the parent's objects out of the collector's reach, so the child's garbage
        # collections do not touch (and copy) the whole inherited heap: ~2x faster with a big parent.
        gc.freeze()
        pid = os.fork()
        if pid == 0:
            _translate_in_child(domain, problem, work, memory_mb)
        gc.unfreeze()
        returncode = _wait(pid, deadline)
        log, sas = work / "translate.log", work / "task.sas"
        output = log.read_text(encoding="utf-8", errors="replace") if log.exists() else ""
        product = sas.read_text(encoding="utf-8") if returncode == 0 and sas.exists() else None
    return _Run(returncode, time.perf_counter() - started, output, product)


_PLAN_LINE = re.compile(r"^\(([^()\s]+)((?:\s+[^()\s]+)*)\)\s*$")


def parse_plan(text: str) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """Return the actions of an FD plan file, skipping its ``; cost`` comment."""
    actions = []
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith(";"):
            continue
        match = _PLAN_LINE.match(line)
        if match is None:
            raise ValueError(f"unexpected line in Fast Downward's plan: {line!r}")
        actions.append((match.group(1), tuple(match.group(2).split())))
    return tuple(actions)


def _tail(output: str, lines: int = 8) -> str:
    return "\n".join(output.strip().splitlines()[-lines:])


def _failure(stage: str, run: _Run, time_limit: float, timing: dict[str, float]) -> SearchOutcome:
    """Return the outcome of a ``stage`` ("translator" or "search") stopped at the deadline or ended without a plan."""
    if run.returncode is None:
        return SearchOutcome(
            PlanStatus.TIMEOUT, timing=timing, message=f"The {stage} did not finish within {time_limit:g} s."
        )
    status = status_of_exit_code(run.returncode)
    message = (
        f"{stage.capitalize()} exit code {run.returncode}: {_tail(run.output)}" if status is PlanStatus.ERROR else ""
    )
    return SearchOutcome(status, timing=timing, message=message)


SOLVE_CACHE_SIZE = int(os.environ.get("CAUSALPLAN_SOLVE_CACHE_SIZE", "512"))
"""Answers kept in memory (``CAUSALPLAN_SOLVE_CACHE_SIZE``; 0 turns the cache off)."""
_solved: OrderedDict[tuple[str, str, str], SearchOutcome] = OrderedDict()
_solved_lock = threading.Lock()


def _solve_uncached(
    domain: str,
    problem: str,
    config: SearchConfig,
    time_limit: float = DEFAULT_TIME_LIMIT,
    memory_limit_mb: int = DEFAULT_MEMORY_LIMIT_MB,
) -> SearchOutcome:
    """Translate and search one PDDL task with FD; never raises for planner failures."""
    try:
        binary = search_binary()
    except PlannerUnavailableError as exc:
        return SearchOutcome(PlanStatus.ERROR, message=exc.message)
    deadline = time.monotonic() + time_limit
    timing: dict[str, float] = {}
    translate = _translate(domain, problem, deadline, memory_limit_mb)
    timing["translate"] = translate.seconds
    if translate.returncode != 0:
        return _failure("translator", translate, time_limit, timing)
    if translate.product is None:
        return SearchOutcome(
            PlanStatus.ERROR, timing=timing, message="The translator reported success but wrote no task."
        )
    sas = translate.product.encode("utf-8")
    search = _search(_search_command(binary, config.search), sas, deadline, memory_limit_mb)
    timing["search"] = search.seconds
    if search.returncode == INCOMPLETE_EXIT:
        # The search gave up without proof (its heuristics may prune); a blind A* proves it.
        search = _search(_search_command(binary, COMPLETE), sas, deadline, memory_limit_mb)
        timing["confirm"] = search.seconds
    if search.returncode is None or status_of_exit_code(search.returncode) is not PlanStatus.SOLVED:
        return _failure("search", search, time_limit, timing)
    if search.product is None:
        return SearchOutcome(PlanStatus.ERROR, timing=timing, message="FD reported success but wrote no plan.")
    return SearchOutcome(PlanStatus.SOLVED, parse_plan(search.product), timing)


def solve(
    domain: str,
    problem: str,
    config: SearchConfig,
    time_limit: float = DEFAULT_TIME_LIMIT,
    memory_limit_mb: int = DEFAULT_MEMORY_LIMIT_MB,
) -> SearchOutcome:
    """Translate and search one PDDL task with FD; never raises for planner failures.

    Definite answers (a plan, or proof there is none) are kept in a bounded in-memory cache
    keyed by the exact PDDL texts and configuration: FD is deterministic, so a repeated task
    gets the same answer without running it (``timing`` then has only ``cached``).
    """
    key = (config.search, domain, problem)
    started = time.perf_counter()
    with _solved_lock:
        known = _solved.get(key)
        if known is not None:
            _solved.move_to_end(key)
    if known is not None:
        return replace(known, timing={"cached": time.perf_counter() - started})
    outcome = _solve_uncached(domain, problem, config, time_limit, memory_limit_mb)
    if SOLVE_CACHE_SIZE > 0 and outcome.status in (PlanStatus.SOLVED, PlanStatus.UNSOLVABLE):
        with _solved_lock:
            _solved[key] = outcome
            while len(_solved) > SOLVE_CACHE_SIZE:
                _solved.popitem(last=False)
    return outcome


def clear_solve_cache() -> None:
    """Forget every cached answer (tests and benchmarks that time real runs use it)."""
    with _solved_lock:
        _solved.clear()


def prestart(config: SearchConfig = CONFIGS["fd"]) -> None:
    """Start the search process for ``config`` in the background now, so a later solve finds it ready.

    A service worker calls it while it starts. Does nothing when prestarting is off or FD's
    binary is missing (the solve reports that).
    """
    if not _prestart_enabled():
        return
    try:
        binary = search_binary()
    except PlannerUnavailableError:
        return
    search_processes.prestart(_search_command(binary, config.search))
