"""Compilation of a causal model and an object into PDDL 2.2 with derived predicates (pure)."""
