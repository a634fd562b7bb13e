"""Fast Downward, run directly on our PDDL: the only module that starts planner processes.

Each solve has a private temporary directory (so concurrent solves never share FD's
``output.sas``), a memory limit and a time limit. The translator is FD's Python package:
on the main thread it runs in this process (no start-up at all; an alarm stops it at the
deadline, RLIMIT_AS bounds its memory), on other threads in a forked copy of this process
that is killed at the deadline. The search binary runs as its own process group, killed at
the deadline. Exit codes map to ``PlanStatus`` in one place.
"""

from __future__ import annotations

import contextlib
import gc
import logging
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

from causalplan.errors import PlannerUnavailableError
from causalplan.planners.result import PlanStatus, SearchOutcome

logger = logging.getLogger(__name__)

DEFAULT_TIME_LIMIT = 30.0
DEFAULT_MEMORY_LIMIT_MB = 2048

LAMA_FIRST = (
    "let(hlm, eval_modify_costs(landmark_sum(lm_factory=lm_reasonable_orders_hps(lm_rhw()),pref=false),"
    "cost_type=one),let(hff, eval_modify_costs(ff(),cost_type=one),"
    "lazy_greedy([hff,hlm],preferred=[hff,hlm],cost_type=one,reopen_closed=false)))"
)
OPTIMAL = "astar(hmax())"
"""A* with h^max: admissible with derived predicates (ours never occur negated)."""
COMPLETE = "astar(blind())"
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


def _limits(memory_mb: int) -> Callable[[], None]:
    def apply() -> None:
        limit = memory_mb * 1024 * 1024
        _soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        if hard != resource.RLIM_INFINITY:  # a parent's limit (e.g. a comparison worker's) cannot be raised
            limit = min(limit, hard)
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    return apply


def _limit_process(pid: int, memory_mb: int) -> None:
    limit = memory_mb * 1024 * 1024
    _soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    with contextlib.suppress(ProcessLookupError):  # it has already finished
        resource.prlimit(pid, resource.RLIMIT_AS, (limit, limit))


@dataclass(frozen=True)
class _Run:
    returncode: int | None  # None: killed at the time limit
    seconds: float
    output: str


def _run(command: list[str], cwd: Path, deadline: float, memory_mb: int, stdin_path: Path | None = None) -> _Run:
    """Run one FD component in its own process group; kill the group at ``deadline``."""
    logger.debug("running (cwd %s): %s", cwd, shlex.join(command))
    started = time.perf_counter()
    stdin = stdin_path.open("rb") if stdin_path else subprocess.DEVNULL
    try:
        process = subprocess.Popen(
            command,
            cwd=cwd,
            stdin=stdin,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        # Limited right after the start rather than in a preexec_fn: that would stop Python
        # from using vfork, and spawning from a large process would cost ~10 ms more.
        _limit_process(process.pid, memory_mb)
        try:
            output, _ = process.communicate(timeout=max(0.0, deadline - time.monotonic()))
            returncode: int | None = process.returncode
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            output, _ = process.communicate()
            returncode = None
    finally:
        if stdin_path and not isinstance(stdin, int):
            stdin.close()
    return _Run(returncode, time.perf_counter() - started, output.decode("utf-8", "replace"))


TRANSLATE_OUT_OF_MEMORY = 20
TRANSLATE_CRITICAL_ERROR = 30
TRANSLATE_INPUT_ERROR = 31


def _run_translator(work: Path) -> int:
    """Run FD's translator on ``work``'s files in this process; return its exit code.

    Paths are absolute and the SAS file is named, so nothing depends on the working folder.
    """
    from fast_downward.translate import main, options, pddl_parser

    options.set_options([str(work / "domain.pddl"), str(work / "problem.pddl"), "--sas-file", str(work / "task.sas")])
    try:
        main.main()
    except MemoryError:
        return TRANSLATE_OUT_OF_MEMORY
    except pddl_parser.ParseError as exc:
        print(exc)
        return TRANSLATE_INPUT_ERROR
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else TRANSLATE_CRITICAL_ERROR
    return 0


def _translate_in_child(work: Path, memory_mb: int) -> int:
    """Run FD's translator in this (forked) process; return its exit code. Never returns normally."""
    log = os.open(work / "translate.log", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    os.dup2(log, 1)
    os.dup2(log, 2)
    code = TRANSLATE_CRITICAL_ERROR
    try:
        _limits(memory_mb)()
        code = _run_translator(work)
    except BaseException:  # noqa: BLE001 - anything else is the translator's critical error
        import traceback

        traceback.print_exc()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


class _TranslatorTimeout(Exception):
    """Raised by the alarm inside an in-process translation that reached its deadline."""


def _translate_here(work: Path, deadline: float, memory_mb: int) -> _Run:
    """Translate in this process (main thread only): no fork, no start-up; limits by alarm and rlimit.

    FD's translator keeps module state between runs, but rebuilds all of it from the options
    and files of each run (tests check that its output is byte-identical to a fresh process's).
    """
    import io

    started = time.perf_counter()
    remaining = deadline - time.monotonic()
    if remaining <= 0:
        return _Run(None, 0.0, "")
    captured = io.StringIO()

    def on_alarm(signum: int, frame: object) -> None:
        raise _TranslatorTimeout

    previous_handler = signal.signal(signal.SIGALRM, on_alarm)
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = memory_mb * 1024 * 1024 if hard == resource.RLIM_INFINITY else min(memory_mb * 1024 * 1024, hard)
    returncode: int | None
    try:
        resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
        signal.setitimer(signal.ITIMER_REAL, remaining)
        with contextlib.redirect_stdout(captured), contextlib.redirect_stderr(captured):
            returncode = _run_translator(work)
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
    return _Run(returncode, time.perf_counter() - started, captured.getvalue())


def _translator_in_process() -> bool:
    """Return whether to translate in this process: only on the main thread (alarms need it)."""
    if os.environ.get("CAUSALPLAN_TRANSLATOR", "in-process") == "fork":
        return False
    return threading.current_thread() is threading.main_thread()


def _wait(pid: int, deadline: float) -> int | None:
    """Wait for child ``pid`` until ``deadline``; return its exit code, or None after killing it."""
    pidfd = os.pidfd_open(pid)
    try:
        ready, _, _ = select.select([pidfd], [], [], max(0.0, deadline - time.monotonic()))
    finally:
        os.close(pidfd)
    if not ready:
        os.kill(pid, signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status) if ready else None


def _translate(work: Path, deadline: float, memory_mb: int) -> _Run:
    """Run the translator on ``work``'s domain.pddl and problem.pddl, writing task.sas."""
    import fast_downward.translate.main  # noqa: F401 - imported once here, so the fork has it

    if _translator_in_process():
        return _translate_here(work, deadline, memory_mb)
    started = time.perf_counter()
    sys.stdout.flush()
    sys.stderr.flush()
    # Freezing moves the parent's objects out of the collector's reach, so the child's garbage
    # collections do not touch (and copy) the whole inherited heap: ~2x faster with a big parent.
    gc.freeze()
    pid = os.fork()
    if pid == 0:
        _translate_in_child(work, memory_mb)
    gc.unfreeze()
    returncode = _wait(pid, deadline)
    log = work / "translate.log"
    output = log.read_text(encoding="utf-8", errors="replace") if log.exists() else ""
    return _Run(returncode, time.perf_counter() - started, output)


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
    with tempfile.TemporaryDirectory(prefix="causalplan-fd-") as folder:
        work = Path(folder)
        (work / "domain.pddl").write_text(domain, encoding="utf-8")
        (work / "problem.pddl").write_text(problem, encoding="utf-8")
        translate = _translate(work, deadline, memory_limit_mb)
        timing["translate"] = translate.seconds
        if translate.returncode is None:
            return SearchOutcome(
                PlanStatus.TIMEOUT, timing=timing, message=f"The translator did not finish within {time_limit:g} s."
            )
        if translate.returncode != 0:
            status = status_of_exit_code(translate.returncode)
            return SearchOutcome(
                status,
                timing=timing,
                message=f"Translator exit code {translate.returncode}: {_tail(translate.output)}"
                if status is PlanStatus.ERROR
                else "",
            )
        search = _run(
            [str(binary), "--search", config.search, "--internal-plan-file", "plan"],
            work,
            deadline,
            memory_limit_mb,
            stdin_path=work / "task.sas",
        )
        timing["search"] = search.seconds
        if search.returncode == INCOMPLETE_EXIT:
            # The search gave up without proof (its heuristics may prune); a blind A* proves it.
            search = _run(
                [str(binary), "--search", COMPLETE, "--internal-plan-file", "plan"],
                work,
                deadline,
                memory_limit_mb,
                stdin_path=work / "task.sas",
            )
            timing["confirm"] = search.seconds
        if search.returncode is None:
            return SearchOutcome(
                PlanStatus.TIMEOUT, timing=timing, message=f"The search did not finish within {time_limit:g} s."
            )
        status = status_of_exit_code(search.returncode)
        if status is not PlanStatus.SOLVED:
            message = (
                f"Search exit code {search.returncode}: {_tail(search.output)}" if status is PlanStatus.ERROR else ""
            )
            return SearchOutcome(status, timing=timing, message=message)
        plan_file = work / "plan"
        if not plan_file.exists():
            return SearchOutcome(PlanStatus.ERROR, timing=timing, message="FD reported success but wrote no plan.")
        return SearchOutcome(PlanStatus.SOLVED, parse_plan(plan_file.read_text(encoding="utf-8")), timing)


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
