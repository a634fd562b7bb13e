"""Models and trials have owners, sizes and expiry: they count in their client's storage allowance.

Rows stored before have no owner and never expire (the participant pages' own rows neither).

Revision ID: 0010
Revises: 0009
Create Date: 2026-12-05
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision: str = "0010"
down_revision: str | None = "0009"
branch_labels: str | None = None
depends_on: str | None = None

TABLES = ("models", "trials")


def upgrade() -> None:
    for table in TABLES:
        with op.batch_alter_table(table) as batch:
            batch.add_column(sa.Column("owner", sa.String(length=160), nullable=True))
            batch.add_column(sa.Column("stored_bytes", sa.Integer(), server_default="0", nullable=False))
            batch.add_column(sa.Column("expires_at", sa.DateTime(timezone=True), nullable=True))
            batch.create_index(f"ix_{table}_owner", ["owner"])
            batch.create_index(f"ix_{table}_expires_at", ["expires_at"])


def downgrade() -> None:
    for table in TABLES:
        with op.batch_alter_table(table) as batch:
            batch.drop_index(f"ix_{table}_expires_at")
            batch.drop_index(f"ix_{table}_owner")
            batch.drop_column("expires_at")
            batch.drop_column("stored_bytes")
            batch.drop_column("owner")
