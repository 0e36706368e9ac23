"""user agent optional, page load time of a step

Revision ID: 0002
Revises: 0001
Create Date: 2026-11-23 04:40:00

``sessions.user_agent`` becomes nullable (stored only when the study collects it);
``selections.load_ms`` and ``restarts.load_ms`` hold the page's reported load time of the
population (generation 0: page, model and textures). Rows recorded before keep their values. SQLite rebuilds ``sessions`` (copy, drop, rename):
:func:`emogen.study.migrations.upgrade` turns its foreign keys off around it and checks them.
"""

import sqlalchemy as sa
from alembic import op

revision = "0002"
down_revision = "0001"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("sessions") as batch:
        batch.alter_column("user_agent", existing_type=sa.String(length=256), nullable=True)
    for table in ("selections", "restarts"):
        with op.batch_alter_table(table) as batch:
            batch.add_column(sa.Column("load_ms", sa.Float(), nullable=True))


def downgrade() -> None:
    for table in ("selections", "restarts"):
        with op.batch_alter_table(table) as batch:
            batch.drop_column("load_ms")
    op.execute("UPDATE sessions SET user_agent = '' WHERE user_agent IS NULL")
    with op.batch_alter_table("sessions") as batch:
        batch.alter_column("user_agent", existing_type=sa.String(length=256), nullable=False)
