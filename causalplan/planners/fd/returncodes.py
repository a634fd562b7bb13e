"""Fast Downward's exit codes, named as in its ``driver/returncodes.py``, and what each means here."""

from __future__ import annotations

import signal
from enum import IntEnum

from causalplan.planners.result import PlanStatus


class ExitCode(IntEnum):
    """The exit codes of FD's translator and search (the translator's are 10, 20, 21, 30, 31)."""

    SUCCESS = 0
    SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY = 1
    SEARCH_PLAN_FOUND_AND_OUT_OF_TIME = 2
    SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY_AND_TIME = 3

    TRANSLATE_UNSOLVABLE = 10
    SEARCH_UNSOLVABLE = 11
    SEARCH_UNSOLVED_INCOMPLETE = 12

    TRANSLATE_OUT_OF_MEMORY = 20
    TRANSLATE_OUT_OF_TIME = 21
    SEARCH_OUT_OF_MEMORY = 22
    SEARCH_OUT_OF_TIME = 23
    SEARCH_OUT_OF_MEMORY_AND_TIME = 24

    TRANSLATE_CRITICAL_ERROR = 30
    TRANSLATE_INPUT_ERROR = 31
    SEARCH_CRITICAL_ERROR = 32
    SEARCH_INPUT_ERROR = 33
    SEARCH_UNSUPPORTED = 34
    DRIVER_CRITICAL_ERROR = 35
    DRIVER_INPUT_ERROR = 36
    DRIVER_UNSUPPORTED = 37

    def is_unrecoverable(self) -> bool:
        """Return whether the code is an error no retry fixes (FD's own helper of that name)."""
        return self >= ExitCode.TRANSLATE_CRITICAL_ERROR

    def found_plan(self) -> bool:
        """Return whether a plan was written (perhaps before running out of time or memory)."""
        return self <= ExitCode.SEARCH_PLAN_FOUND_AND_OUT_OF_MEMORY_AND_TIME

    def status(self) -> PlanStatus:
        """Return the planner outcome this code stands for."""
        if self.found_plan():
            return PlanStatus.SOLVED
        if self in (ExitCode.TRANSLATE_UNSOLVABLE, ExitCode.SEARCH_UNSOLVABLE):
            return PlanStatus.UNSOLVABLE
        if self in (ExitCode.TRANSLATE_OUT_OF_TIME, ExitCode.SEARCH_OUT_OF_TIME):
            return PlanStatus.TIMEOUT
        if self in (
            ExitCode.TRANSLATE_OUT_OF_MEMORY,
            ExitCode.SEARCH_OUT_OF_MEMORY,
            ExitCode.SEARCH_OUT_OF_MEMORY_AND_TIME,
        ):
            return PlanStatus.OUT_OF_MEMORY
        return PlanStatus.ERROR


def status_of_exit_code(code: int) -> PlanStatus:
    """Return the status of any exit code: FD's named ones, signals (negative) and unknown codes."""
    if code < 0:  # killed by a signal: a segfault is how FD's search dies when memory runs out
        return PlanStatus.OUT_OF_MEMORY if code == -signal.SIGSEGV else PlanStatus.ERROR
    try:
        return ExitCode(code).status()
    except ValueError:
        return PlanStatus.ERROR
