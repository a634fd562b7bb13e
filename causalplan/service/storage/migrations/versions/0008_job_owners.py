"""Jobs have owners, and the bytes each stores: per-client limits on jobs in flight and bytes stored.

Jobs stored before have no owner (''): only the research token sees them.

Revision ID: 0008
Revises: 0007
Create Date: 2026-12-03
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision: str = "0008"
down_revision: str | None = "0007"
branch_labels: str | None = None
depends_on: str | None = None


def upgrade() -> None:
    with op.batch_alter_table("jobs") as batch:
        batch.add_column(sa.Column("owner", sa.String(length=160), server_default="", nullable=False))
        batch.add_column(sa.Column("request_bytes", sa.Integer(), server_default="0", nullable=False))
        batch.add_column(sa.Column("result_bytes", sa.Integer(), server_default="0", nullable=False))
        batch.create_index("ix_jobs_owner_status", ["owner", "status"])


def downgrade() -> None:
    with op.batch_alter_table("jobs") as batch:
        batch.drop_index("ix_jobs_owner_status")
        batch.drop_column("result_bytes")
        batch.drop_column("request_bytes")
        batch.drop_column("owner")
