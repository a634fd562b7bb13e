"""Planners: Fast Downward run directly on our PDDL, plan replay, and the planning pipeline."""
