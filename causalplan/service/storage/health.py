"""What /health asks the database: does it answer, and does a PostgreSQL server take writes."""

from __future__ import annotations

from sqlalchemy import Engine, text


def ping(engine: Engine) -> None:
    """Run the smallest query; raises ``SQLAlchemyError`` when the database does not answer."""
    with engine.connect() as connection:
        connection.execute(text("SELECT 1"))


def is_server_read_only(engine: Engine) -> bool:
    """Return whether a PostgreSQL server refuses writes (a standby, or ``default_transaction_read_only``)."""
    with engine.connect() as connection:
        return bool(connection.execute(text("SHOW transaction_read_only")).scalar() == "on")
