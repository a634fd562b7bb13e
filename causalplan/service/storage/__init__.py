"""Storage: SQLAlchemy 2 records (``models``), the engine (``session``), ``crud``, and the Alembic migrations."""
