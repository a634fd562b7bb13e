"""The ways causalplan runs FD's search: a ``--search`` string each, with a name and a sentence."""

from __future__ import annotations

from dataclasses import dataclass

# Silent: FD's log is read only for the tail of an error.
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
