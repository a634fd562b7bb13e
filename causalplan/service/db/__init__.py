"""Storage: SQLAlchemy 2 records, the engine, and the Alembic migrations."""
