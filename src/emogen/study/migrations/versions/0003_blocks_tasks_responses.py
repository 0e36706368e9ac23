"""blocks and tasks: a trial's block and task, categorise stimuli and responses

Revision ID: 0003
Revises: 0002
Create Date: 2026-11-25 18:20:00

``trials.block`` (0 for every trial recorded before: one evolve block) and ``trials.task``
(``evolve`` for them); ``stimuli`` (the face a categorise trial shows, fixed when its block
starts) and ``responses`` (its answer). Rows recorded before keep their values and replay.
"""

import sqlalchemy as sa
from alembic import op

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("trials") as batch:
        batch.add_column(sa.Column("block", sa.Integer(), server_default="0", nullable=False))
        batch.add_column(
            sa.Column("task", sa.String(length=16), server_default="evolve", nullable=False)
        )
    op.create_table(
        "stimuli",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("trial_id", sa.Integer(), nullable=False),
        sa.Column("source", sa.String(length=16), nullable=False),
        sa.Column("fallback", sa.Boolean(), nullable=False),
        sa.Column("source_session_id", sa.Integer(), nullable=True),
        sa.Column("source_trial", sa.Integer(), nullable=True),
        sa.Column("source_face_id", sa.Integer(), nullable=True),
        sa.Column("source_row", sa.Integer(), nullable=True),
        sa.Column("source_label", sa.String(length=64), nullable=True),
        sa.Column("intended", sa.String(length=64), nullable=True),
        sa.Column("identity", sa.String(length=64), nullable=False),
        sa.Column("genes", sa.Text(), nullable=True),
        sa.Column("weights", sa.Text(), nullable=False),
        sa.Column("labels", sa.Text(), nullable=False),
        sa.Column("shown_at", sa.DateTime(timezone=True), nullable=True),
        sa.ForeignKeyConstraint(["trial_id"], ["trials.id"]),
        sa.PrimaryKeyConstraint("id"),
        sa.UniqueConstraint("trial_id"),
    )
    op.create_table(
        "responses",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("trial_id", sa.Integer(), nullable=False),
        sa.Column("label", sa.String(length=64), nullable=False),
        sa.Column("label_position", sa.Integer(), nullable=False),
        sa.Column("intensity", sa.Integer(), nullable=True),
        sa.Column("confidence", sa.Integer(), nullable=True),
        sa.Column("submitted_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("server_response_ms", sa.Float(), nullable=False),
        sa.Column("client_response_ms", sa.Float(), nullable=True),
        sa.Column("load_ms", sa.Float(), nullable=True),
        sa.Column("step_key", sa.String(length=64), nullable=False),
        sa.ForeignKeyConstraint(["trial_id"], ["trials.id"]),
        sa.PrimaryKeyConstraint("id"),
        sa.UniqueConstraint("trial_id"),
    )


def downgrade() -> None:
    op.drop_table("responses")
    op.drop_table("stimuli")
    with op.batch_alter_table("trials") as batch:
        batch.drop_column("task")
        batch.drop_column("block")
