"""``causalplan compare``: every planner on every task, each run in its own limited process."""
