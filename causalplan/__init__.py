"""causalplan: teach a robot why an object works, then plan with that knowledge.

The pipeline runs in one direction: ``causal`` (a person's model) -> ``objects`` (the
catalog) -> ``pddl`` (compilation) -> ``planners`` -> ``transfer`` -> ``sim`` -> ``service``
and ``cli``. The Python API (see ``causalplan.api``) is re-exported here.
"""

from causalplan.api import InvalidInputError, catalog, load_mapping, load_model, plan, simulate, transfer_verdict
from causalplan.version import __version__

__all__ = [
    "InvalidInputError",
    "__version__",
    "catalog",
    "load_mapping",
    "load_model",
    "plan",
    "simulate",
    "transfer_verdict",
]
