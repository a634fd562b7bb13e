"""Fast Downward on causalplan's PDDL: configurations, translator, search, exit codes, answer cache."""

from causalplan.planners.fd.configs import CONFIGS, SearchConfig
from causalplan.planners.fd.returncodes import ExitCode, status_of_exit_code
from causalplan.planners.fd.search import parse_plan, search_binary, use_search_binary
from causalplan.planners.fd.solve import (
    DEFAULT_MEMORY_LIMIT_MB,
    DEFAULT_TIME_LIMIT,
    prestart,
    solve,
)
from causalplan.planners.fd.translate import translator_available

__all__ = [
    "CONFIGS",
    "DEFAULT_MEMORY_LIMIT_MB",
    "DEFAULT_TIME_LIMIT",
    "ExitCode",
    "SearchConfig",
    "parse_plan",
    "prestart",
    "search_binary",
    "solve",
    "status_of_exit_code",
    "translator_available",
    "use_search_binary",
]
