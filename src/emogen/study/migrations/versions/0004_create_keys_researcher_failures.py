"""session creation keys, and wrong researcher tokens counted in the database

Revision ID: 0004
Revises: 0003
Create Date: 2026-12-02 10:00:00

``sessions.create_key``: the SHA-256 of the key the consent page made before its first try to
create the session, so that a retried create (its answer lost) gets the same session; NULL for
sessions made before. ``researcher_failures``: one token bucket of wrong researcher tokens per
client address, shared by every worker process of every server on the database.
"""

import sqlalchemy as sa
from alembic import op

revision = "0004"
down_revision = "0003"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("sessions") as batch:
        batch.add_column(sa.Column("create_key", sa.String(length=64), nullable=True))
    op.create_index("ix_sessions_create_key", "sessions", ["study_id", "create_key"])
    op.create_table(
        "researcher_failures",
        sa.Column("client", sa.String(length=64), nullable=False),
        sa.Column("tokens", sa.Float(), nullable=False),
        sa.Column("updated", sa.Float(), nullable=False),
        sa.PrimaryKeyConstraint("client"),
    )


def downgrade() -> None:
    op.drop_table("researcher_failures")
    op.drop_index("ix_sessions_create_key", "sessions")
    with op.batch_alter_table("sessions") as batch:
        batch.drop_column("create_key")
