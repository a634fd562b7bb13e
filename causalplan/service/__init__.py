"""The HTTP planning service: FastAPI routes, a planner worker pool, and storage.

Laid out like FastAPI's full-stack template: ``main`` (app factory), ``routes/<resource>.py``,
``deps`` (``Annotated`` dependencies), ``settings`` (one ``Settings``), ``schemas`` (In/Out),
``crud`` and ``db/`` (SQLAlchemy 2 records, Alembic migrations). Nothing below imports it.
"""
