"""The HTTP planning service: FastAPI routes, a planner worker pool, and storage.

By role: ``main`` (app factory, error handlers, middleware), ``routes/<resource>.py``,
``deps`` (``Annotated`` dependencies), ``documents`` (reads and checks what a request sends),
``answers`` (answers it: the answer cache, or the pool), ``pool/`` (pebble's worker processes,
what a worker does, their jobs), ``db/`` (records, sessions, CRUD, Alembic migrations), ``schemas/`` (In/Out
per resource), ``throttle`` (wrong research tokens), ``web/`` (participant and research pages).
Settings are ``causalplan.settings``. Nothing below the service imports it.
"""
