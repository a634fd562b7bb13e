"""An arrival is one platform session: the same platform id with another session is another arrival.

A bot that arrives first with a victim's PROLIFIC_PID (but not their SESSION_ID, which only the
platform's link carries) then neither declines for the victim nor takes their record.

Revision ID: 0007
Revises: 0006
Create Date: 2026-12-02
"""

from __future__ import annotations

from alembic import op

revision: str = "0007"
down_revision: str | None = "0006"
branch_labels: str | None = None
depends_on: str | None = None


def upgrade() -> None:
    with op.batch_alter_table("study_arrivals") as batch:
        batch.drop_constraint("uq_study_arrivals_platform_id", type_="unique")
        batch.create_unique_constraint(
            "uq_study_arrivals_platform_session", ["experiment_id", "platform", "platform_id", "platform_session"]
        )


def downgrade() -> None:
    with op.batch_alter_table("study_arrivals") as batch:
        batch.drop_constraint("uq_study_arrivals_platform_session", type_="unique")
        batch.create_unique_constraint("uq_study_arrivals_platform_id", ["experiment_id", "platform", "platform_id"])
