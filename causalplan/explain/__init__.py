"""Explanations of plans: why this step, why not that one, and what would make a failed model work."""
