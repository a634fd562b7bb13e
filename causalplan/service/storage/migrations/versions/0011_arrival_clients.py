"""Each arrival keeps the client address it came from, so one address cannot hold a study's places.

A client address may hold at most the experiment's ``places_per_client`` places admitted but
not started; the address is the researcher's (the private export shows it, the shareable one
never does).

Revision ID: 0011
Revises: 0010
Create Date: 2026-12-05
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision: str = "0011"
down_revision: str | None = "0010"
branch_labels: str | None = None
depends_on: str | None = None


def upgrade() -> None:
    with op.batch_alter_table("study_arrivals") as batch:
        batch.add_column(sa.Column("client_address", sa.String(64), nullable=True))
        batch.create_index("ix_study_arrivals_client", ["experiment_id", "client_address"])


def downgrade() -> None:
    with op.batch_alter_table("study_arrivals") as batch:
        batch.drop_index("ix_study_arrivals_client")
        batch.drop_column("client_address")
