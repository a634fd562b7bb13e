"""The planner pools: pebble's worker processes (``pool``), what a worker does (``worker``), its jobs (``jobs``)."""
