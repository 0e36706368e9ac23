"""which display an evolve step's faces had: ``fallback`` on selections, restarts and ratings

Revision ID: 0005
Revises: 0004
Create Date: 2026-11-28 10:10:00

``selections.fallback``, ``restarts.fallback``, ``ratings.fallback``: the page showed the
server's images (no WebGL: a still face as a picture, a face that moves as the strip of its
frames) rather than the 3D viewer; NULL for steps recorded before the page said.
"""

import sqlalchemy as sa
from alembic import op

revision = "0005"
down_revision = "0004"
branch_labels = None
depends_on = None

TABLES = ("selections", "restarts", "ratings")


def upgrade() -> None:
    for table in TABLES:
        with op.batch_alter_table(table) as batch:
            batch.add_column(sa.Column("fallback", sa.Boolean(), nullable=True))


def downgrade() -> None:
    for table in TABLES:
        with op.batch_alter_table(table) as batch:
            batch.drop_column("fallback")
