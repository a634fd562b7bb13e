"""Public study links: recruiting settings, places per condition, arrivals and exclusions.

Revision ID: 0004
Revises: 0003
Create Date: 2026-12-01
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision: str = "0004"
down_revision: str | None = "0003"
branch_labels: str | None = None
depends_on: str | None = None


def upgrade() -> None:
    with op.batch_alter_table("experiments") as batch:
        batch.add_column(sa.Column("recruitment", sa.JSON(), nullable=True))
    op.create_table(
        "study_places",
        sa.Column("experiment_id", sa.Uuid(), nullable=False),
        sa.Column("condition", sa.String(length=200), nullable=False),
        sa.Column("taken", sa.Integer(), nullable=False),
        sa.Column("quota", sa.Integer(), nullable=True),
        sa.ForeignKeyConstraint(
            ["experiment_id"],
            ["experiments.id"],
            name=op.f("fk_study_places_experiment_id_experiments"),
            ondelete="RESTRICT",
        ),
        sa.PrimaryKeyConstraint("experiment_id", "condition", name=op.f("pk_study_places")),
    )
    op.create_table(
        "study_arrivals",
        sa.Column("id", sa.Uuid(), nullable=False),
        sa.Column("code", sa.String(length=64), nullable=False),
        sa.Column("experiment_id", sa.Uuid(), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("platform", sa.String(length=16), nullable=False),
        sa.Column("platform_id", sa.String(length=64), nullable=True),
        sa.Column("platform_study", sa.String(length=64), nullable=True),
        sa.Column("platform_session", sa.String(length=64), nullable=True),
        sa.Column("submit_to", sa.String(length=64), nullable=True),
        sa.Column("consented", sa.Boolean(), nullable=True),
        sa.Column("decided_at", sa.DateTime(timezone=True), nullable=True),
        sa.Column("participant_id", sa.Uuid(), nullable=True),
        sa.ForeignKeyConstraint(
            ["experiment_id"],
            ["experiments.id"],
            name=op.f("fk_study_arrivals_experiment_id_experiments"),
            ondelete="RESTRICT",
        ),
        sa.ForeignKeyConstraint(
            ["participant_id"],
            ["participants.id"],
            name=op.f("fk_study_arrivals_participant_id_participants"),
            ondelete="RESTRICT",
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_study_arrivals")),
        sa.UniqueConstraint("code", name=op.f("uq_study_arrivals_code")),
        sa.UniqueConstraint("participant_id", name=op.f("uq_study_arrivals_participant_id")),
        sa.UniqueConstraint("experiment_id", "platform", "platform_id", name="uq_study_arrivals_platform_id"),
    )
    op.create_index(op.f("ix_study_arrivals_experiment_id"), "study_arrivals", ["experiment_id"])
    op.create_table(
        "participant_exclusions",
        sa.Column("id", sa.Uuid(), nullable=False),
        sa.Column("participant_id", sa.Uuid(), nullable=False),
        sa.Column("reason", sa.String(length=32), nullable=False),
        sa.Column("detail", sa.String(length=500), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(
            ["participant_id"],
            ["participants.id"],
            name=op.f("fk_participant_exclusions_participant_id_participants"),
            ondelete="RESTRICT",
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_participant_exclusions")),
    )
    op.create_index(op.f("ix_participant_exclusions_participant_id"), "participant_exclusions", ["participant_id"])


def downgrade() -> None:
    op.drop_index(op.f("ix_participant_exclusions_participant_id"), table_name="participant_exclusions")
    op.drop_table("participant_exclusions")
    op.drop_index(op.f("ix_study_arrivals_experiment_id"), table_name="study_arrivals")
    op.drop_table("study_arrivals")
    op.drop_table("study_places")
    with op.batch_alter_table("experiments") as batch:
        batch.drop_column("recruitment")
