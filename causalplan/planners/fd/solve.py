"""One Fast Downward solve: translate, search (and prove unsolvable if need be), answers cached.

Each solve has its own private folder: the PDDL, the SAS task and the plan live there and go
with it. FD is deterministic, so definite answers (a plan, or proof there is none) are kept in
the process's ``fd_answers`` cache (``causalplan.caches``) by the exact PDDL texts and the
search configuration.
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import replace

from causalplan import caches
from causalplan.caches import BoundedCache
from causalplan.errors import PlannerUnavailableError
from causalplan.planners import processes
from causalplan.planners.fd import idle
from causalplan.planners.fd.configs import COMPLETE, SearchConfig
from causalplan.planners.fd.returncodes import ExitCode, status_of_exit_code
from causalplan.planners.fd.search import parse_plan, search, search_binary, search_command
from causalplan.planners.fd.translate import SAS_FILE, translate
from causalplan.planners.processes import Finished
from causalplan.planners.result import PlanStatus, SearchOutcome

DEFAULT_TIME_LIMIT = 30.0
DEFAULT_MEMORY_LIMIT_MB = 2048


def _answers() -> BoundedCache[tuple[str, str, str], SearchOutcome]:
    return caches.current().fd_answers


def _tail(output: str, lines: int = 8) -> str:
    return "\n".join(output.strip().splitlines()[-lines:])


def _failure(stage: str, run: Finished, time_limit: float, timing: dict[str, float]) -> SearchOutcome:
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


def _solve_uncached(
    domain: str, problem: str, config: SearchConfig, time_limit: float, memory_mb: int
) -> SearchOutcome:
    try:
        search_binary()
    except PlannerUnavailableError as exc:
        return SearchOutcome(PlanStatus.ERROR, message=exc.message)
    deadline = time.monotonic() + time_limit
    timing: dict[str, float] = {}
    with processes.private_folder("causalplan-fd-") as folder:
        translated = translate(domain, problem, folder, time_limit, memory_mb)
        timing["translate"] = translated.seconds
        if translated.returncode != ExitCode.SUCCESS:
            return _failure("translator", translated, time_limit, timing)
        try:
            sas = (folder / SAS_FILE).read_bytes()
        except FileNotFoundError:
            return SearchOutcome(
                PlanStatus.ERROR, timing=timing, message="The translator ended well but wrote no task."
            )
        searched, plan = search(sas, config.search, folder, deadline - time.monotonic(), memory_mb)
        timing["search"] = searched.seconds
        if searched.returncode == ExitCode.SEARCH_UNSOLVED_INCOMPLETE:
            # The search gave up without proof (its heuristics may prune); a blind A* proves it.
            searched, plan = search(sas, COMPLETE, folder, deadline - time.monotonic(), memory_mb)
            timing["confirm"] = searched.seconds
        if searched.returncode is None or status_of_exit_code(searched.returncode) is not PlanStatus.SOLVED:
            return _failure("search", searched, time_limit, timing)
        if plan is None:
            return SearchOutcome(PlanStatus.ERROR, timing=timing, message="FD reported a plan but wrote none.")
    return SearchOutcome(PlanStatus.SOLVED, parse_plan(plan), timing)


def solve(
    domain: str,
    problem: str,
    config: SearchConfig,
    time_limit: float = DEFAULT_TIME_LIMIT,
    memory_limit_mb: int = DEFAULT_MEMORY_LIMIT_MB,
) -> SearchOutcome:
    """Translate and search one PDDL task with FD; never raises for planner failures.

    A repeated task gets its cached answer (``timing`` then has only ``cached``).
    """
    answers = _answers()
    key = (config.search, domain, problem)
    started = time.perf_counter()
    known = answers.get(key)
    if known is not None:
        return replace(known, timing={"cached": time.perf_counter() - started})
    outcome = _solve_uncached(domain, problem, config, time_limit, memory_limit_mb)
    if outcome.status.is_final():
        answers.put(key, outcome)
    return outcome


def prestart(config: SearchConfig) -> None:
    """Keep a search process for ``config`` started ahead from now on (a service worker calls it once)."""
    with contextlib.suppress(PlannerUnavailableError):  # the solve that needs it reports that
        idle.prestart(search_command(config.search))
