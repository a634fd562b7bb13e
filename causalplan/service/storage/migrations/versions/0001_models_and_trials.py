"""Models and transfer trials.

Revision ID: 0001
Revises:
Create Date: 2026-11-23
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision: str = "0001"
down_revision: str | None = None
branch_labels: str | None = None
depends_on: str | None = None


def upgrade() -> None:
    op.create_table(
        "models",
        sa.Column("id", sa.Uuid(), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("participant_id", sa.String(length=128), nullable=True),
        sa.Column("session_id", sa.String(length=128), nullable=True),
        sa.Column("object_id", sa.String(length=200), nullable=False),
        sa.Column("is_valid", sa.Boolean(), nullable=False),
        sa.Column("canonical_hash", sa.String(length=64), nullable=True),
        sa.Column("document", sa.JSON(), nullable=False),
        sa.Column("report", sa.JSON(), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_models")),
    )
    op.create_index(op.f("ix_models_created_at"), "models", ["created_at"])
    op.create_index(op.f("ix_models_participant_id"), "models", ["participant_id"])
    op.create_index(op.f("ix_models_session_id"), "models", ["session_id"])
    op.create_index(op.f("ix_models_canonical_hash"), "models", ["canonical_hash"])
    op.create_table(
        "trials",
        sa.Column("id", sa.Uuid(), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("participant_id", sa.String(length=128), nullable=True),
        sa.Column("session_id", sa.String(length=128), nullable=True),
        sa.Column("model_id", sa.Uuid(), nullable=False),
        sa.Column("mapping", sa.JSON(), nullable=False),
        sa.Column("training_object", sa.String(length=200), nullable=True),
        sa.Column("test_object", sa.String(length=200), nullable=True),
        sa.Column("planner", sa.String(length=64), nullable=False),
        sa.Column("verdict", sa.String(length=32), nullable=False),
        sa.Column("generalization", sa.String(length=32), nullable=True),
        sa.Column("decided_by", sa.String(length=32), nullable=False),
        sa.Column("cached", sa.Boolean(), nullable=False),
        sa.Column("seconds", sa.Float(), nullable=False),
        sa.Column("result", sa.JSON(), nullable=False),
        sa.ForeignKeyConstraint(
            ["model_id"], ["models.id"], name=op.f("fk_trials_model_id_models"), ondelete="RESTRICT"
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_trials")),
    )
    op.create_index(op.f("ix_trials_created_at"), "trials", ["created_at"])
    op.create_index(op.f("ix_trials_session_id"), "trials", ["session_id"])
    op.create_index(op.f("ix_trials_model_id"), "trials", ["model_id"])
    op.create_index(op.f("ix_trials_verdict"), "trials", ["verdict"])
    op.create_index("ix_trials_participant_created", "trials", ["participant_id", "created_at"])


def downgrade() -> None:
    op.drop_table("trials")
    op.drop_table("models")
