"""The paper's probabilistic MDP: fits succeed with a probability, the causal model gives the reward.

The model (paper, "Planner"): a state is the assembly state, an action attempts one fit, the
transition probability is the fit's success probability from the catalog, and the reward comes
from the person's causal model (``model.py`` says exactly how). Planner ``mdp`` is
``composed.solve_by_components``: improved LAO* from the start state with an admissible bound
(``search.py``), then independent components solved apart (``components.py``) and a solver that
splits after every attempt (``split.py``); ``exact.solve_mdp`` (every reachable state, planner
``mdp-exact``) is the reference. ``objective.solve_for`` chooses what is optimised.
"""

from causalplan.planners.mdp.exact import MAX_RELEVANT_FITS, solve_mdp
from causalplan.planners.mdp.model import (
    STEP_COST,
    MdpSolution,
    Objective,
    Optimality,
    relevant_fits,
    search_outcome,
)
from causalplan.planners.mdp.search import solve_mdp_search

__all__ = [
    "MAX_RELEVANT_FITS",
    "STEP_COST",
    "MdpSolution",
    "Objective",
    "Optimality",
    "relevant_fits",
    "search_outcome",
    "solve_mdp",
    "solve_mdp_search",
]
