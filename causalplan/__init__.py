"""causalplan: teach a robot why an object works, then plan with that knowledge.

The pipeline runs in one direction: ``causal`` (a person's model) -> ``objects`` (the
catalog) -> ``pddl`` (compilation) -> ``planners`` -> ``transfer`` -> ``cli``.
"""

__version__ = "0.1.0"
