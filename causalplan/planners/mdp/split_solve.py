"""The splitting solver's passes, and its policy: an agenda of residual groups (``split.py`` solves them).

The first pass forces every clean attempt and proves the most reliable policy; two finer passes,
bounded by its exact values, look for fewer expected attempts among equally reliable options
(docs/planners.md, "Forced attempts and fits that cannot help").
"""

from __future__ import annotations

import math
import sys
import time

from causalplan.planners.mdp.model import CompiledMdp, MdpSolution, State, all_success_path, policy_entries, unsolvable
from causalplan.planners.mdp.split import TIE, Key, SplitStopped, Splitter
from causalplan.planners.result import PlanStatus

FINER_PASSES = ((0, 0.1), (1, 0.2))
"""The passes after the first: (``Splitter.force``, their share of the time). Nothing forced
branches the most, so it has the smaller share; when it finishes its attempts are this
solver's fewest and the second pass is skipped."""


class SplitPolicy:
    """The agenda policy: replay a state's outcomes from the start; the first fit not yet tried is next."""

    def __init__(self, splitter: Splitter, start: tuple[Key, ...]) -> None:
        self.splitter = splitter
        self.start = start

    def agenda(self, state: State) -> tuple[list[Key], int]:
        """Return the residuals still to run in ``state`` and the fit to attempt (-1: the run is over)."""
        made, failed = state
        agenda = list(self.start)
        while agenda:
            entry = self.splitter.memo[agenda[0]]
            if entry.action < 0:
                if entry.success == 0.0:
                    return agenda, -1
                agenda.pop(0)
                continue
            bit = 1 << entry.action
            if made & bit:
                agenda[:1] = entry.on_success
            elif failed & bit:
                agenda[:1] = entry.on_failure
            else:
                return agenda, entry.action
        return agenda, -1

    def __call__(self, state: State) -> int:
        return self.agenda(state)[1]

    def success(self, state: State) -> float:
        """Return the policy's success probability from ``state``."""
        agenda, _ = self.agenda(state)
        return math.prod(self.splitter.memo[residual].success for residual in agenda)


def solve_split(compiled: CompiledMdp, time_limit: float) -> MdpSolution | None:
    """Return the exact solution by splitting after every attempt; None when it does not finish in time.

    First with every clean attempt forced (``Splitter.forced``): the most reliable policy,
    proved, quickly. Its exact values then bound two finer passes, so only equally reliable
    options are solved, for fewer expected attempts: nothing forced (a tenth of the time), else
    only the necessary parts' clean attempts (a fifth). The policy with the fewest expected
    attempts among the passes that finished is the answer (the success probability is the same).
    """
    started = time.monotonic()
    deadline = started + time_limit
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 8 * len(compiled.fits) + 200))
    try:
        first = splitter = Splitter(compiled, deadline)
        start = splitter.groups(compiled.base, 0, tuple(splitter.support), splitter.all_fits)
        success, attempts, order = splitter.combined(start)
        finer: list[Splitter] = []
        for force, share in FINER_PASSES:
            finer.append(Splitter(compiled, min(deadline, time.monotonic() + share * time_limit), force, first))
            try:
                fine_success, fine_attempts, fine_order = finer[-1].combined(start)
            except SplitStopped:
                continue
            if abs(fine_success - success) <= TIE and fine_attempts < attempts - TIE:
                splitter, success, attempts, order = finer[-1], fine_success, fine_attempts, fine_order
            if force == 0:
                break  # nothing forced: the fewest attempts of this solver
    except SplitStopped:
        return None
    finally:
        sys.setrecursionlimit(limit)
    residuals = len(first.memo) + sum(len(each.memo) for each in finer)
    fits = compiled.fits
    if success == 0.0:
        return unsolvable(fits, residuals, "No policy reaches the goal.")
    policy = SplitPolicy(splitter, order)
    return MdpSolution(
        PlanStatus.SOLVED,
        all_success_path(fits, policy)[0],
        success,
        attempts,
        policy_entries(compiled, policy, policy.success),
        residuals,
        len(fits),
        f"Proved the most reliable policy by splitting the rest into independent groups after every attempt "
        f"({residuals:,} residual groups); the groups run whole, in Smith's ratio order.",
        success_upper=success,
        fits=fits,
        decider=policy,
        fewest_attempts=False,
    )
