"""The planner pool: worker processes (``process``), their loop (``worker``), the jobs they run (``jobs``)."""
