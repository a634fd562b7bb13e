"""Troubleshooting: a broken object, one faulty part, and the fewest expected actions to repair it.

A person's causal model says which parts can be to blame; the exact solver turns that (or no
model, or the catalog's priors) into a policy of tests, inspections, detachments and
replacements. See ``docs/troubleshooting.md``.
"""
