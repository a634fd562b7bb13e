"""Research sign-in cookies signed out before they lapse.

Revision ID: 0003
Revises: 0002
Create Date: 2026-12-01
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision: str = "0003"
down_revision: str | None = "0002"
branch_labels: str | None = None
depends_on: str | None = None


def upgrade() -> None:
    op.create_table(
        "revoked_research_sessions",
        sa.Column("id", sa.String(length=64), nullable=False),
        sa.Column("expires_at", sa.DateTime(timezone=True), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_revoked_research_sessions")),
    )
    op.create_index(op.f("ix_revoked_research_sessions_expires_at"), "revoked_research_sessions", ["expires_at"])


def downgrade() -> None:
    op.drop_index(op.f("ix_revoked_research_sessions_expires_at"), table_name="revoked_research_sessions")
    op.drop_table("revoked_research_sessions")
