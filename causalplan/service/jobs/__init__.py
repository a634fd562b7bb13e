"""Long work asked over HTTP as jobs: the kinds (``kinds``), the table's reads and writes (``store``), the runner.

"Job" means only this: queued, leased work. A job is a row in the ``jobs`` table that any
replica can answer for; its work is done by some replica's runner, through the work layer
(``service.work``: the functions a worker process runs) on the jobs' own pool, or on a Dask
cluster.
"""
