"""Long work asked over HTTP as jobs: the kinds (``kinds``), the table's reads and writes (``store``), the runner.

Not to be confused with ``service.pool.jobs``: the functions a planner worker process runs.
A job here is a row in the ``jobs`` table that any replica can answer for; its work is done
by some replica's runner, in that replica's planner workers or on a Dask cluster.
"""
