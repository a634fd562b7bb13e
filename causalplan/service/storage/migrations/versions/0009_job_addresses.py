"""Jobs of clients without a key keep the address that posted them: per-address caps, the anonymous share.

A job with an address is anonymous work (an address's own, or a participant's film): the
anonymous jobs together may take only part of the service's cap, and each address has a cap.
Jobs stored before by an address owner get that address back from the owner.

Revision ID: 0009
Revises: 0008
Create Date: 2026-12-05
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision: str = "0009"
down_revision: str | None = "0008"
branch_labels: str | None = None
depends_on: str | None = None

ADDRESS_PREFIX = "address:"


def upgrade() -> None:
    with op.batch_alter_table("jobs") as batch:
        batch.add_column(sa.Column("address", sa.String(length=64), nullable=True))
        batch.create_index("ix_jobs_address_status", ["address", "status"])
    jobs = sa.table("jobs", sa.column("owner", sa.String()), sa.column("address", sa.String()))
    op.execute(
        jobs.update()
        .where(jobs.c.owner.like(f"{ADDRESS_PREFIX}%"))
        .values(address=sa.func.substr(jobs.c.owner, len(ADDRESS_PREFIX) + 1, 64))
    )


def downgrade() -> None:
    with op.batch_alter_table("jobs") as batch:
        batch.drop_index("ix_jobs_address_status")
        batch.drop_column("address")
