"""The HTTP planning service: the JSON API, the participant and research pages, jobs, workers and storage.

By role (``docs/architecture.md`` has the map and two requests followed file by file):
``main`` (the app: routers, error handlers, middleware, start-up and shutdown), ``deps``
(``Services`` and the routes' ``Annotated`` dependencies), ``api/routes/<resource>.py`` (every
``/v1`` route) with ``api/schemas/`` (In/Out per resource), ``pages/`` (participant and research
pages, templates, static files), ``documents`` (reads and checks what a request sends),
``work/`` (the work layer: every function a worker process runs, and ``Workers``, the one way to
run them, through the answer cache or not), ``pool/`` (the worker processes, used only by the
work layer and ``main``/``deps``), ``jobs/`` (queued, leased work: kinds, requests, the runner),
``storage/`` (every query: records, sessions, CRUD, throttles, Alembic migrations), ``owners``
(who a job belongs to, and each one's limits), ``experiments``, ``caches``, ``responses`` and
``errors``. Settings are ``causalplan.settings``. Nothing below the service imports it.
"""
