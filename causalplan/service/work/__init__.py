"""The work layer: every function the service runs in a worker process, and the one way to run it.

``registry`` lists the work (``WORK``: each ``Work`` with its typed arguments, time limit and
pool); ``planning``, ``robot``, ``pictures`` and ``batches`` are the functions a worker runs;
``calls.Workers`` (on ``Services.work``) runs them, through the answer cache or not. Only this
layer and the app's wiring (``main``, ``deps``) import ``service.pool``, the processes themselves.
"""
