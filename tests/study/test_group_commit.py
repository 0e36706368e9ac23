"""SQLite group commit: the jobs of one batch share a transaction but not their ORM objects."""

from __future__ import annotations

from concurrent.futures import Future
from pathlib import Path
from typing import Any

from sqlalchemy import update
from sqlalchemy.orm import Session

from emogen.study.queries import session_by_token
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, core_table
from tests.study.drive import study_service


def test_a_job_sees_what_an_earlier_job_of_its_batch_wrote_by_a_plain_statement(
    tmp_path: Path, small_study: Any, ict_model: Any
) -> None:
    """A selection writes by plain statements; a later job in the same batch (the same ORM
    session) must read the row as it is, not an object an earlier job loaded before."""
    store = Store(f"sqlite:///{tmp_path / 'study.sqlite'}")
    try:
        service = study_service(small_study, store, ict_model)
        token, _ = service.create_session("BATCH-1")
        study_ids = service.ctx.accepted
        table = core_table(SessionRow)

        def keep(db: Session) -> SessionRow:
            return session_by_token(db, token, study_ids)  # still referenced after the job

        def load(db: Session) -> str:
            return session_by_token(db, token, study_ids).stage

        def change(db: Session) -> None:
            db.connection().execute(
                update(table).where(table.c.token == token).values(stage="trial")
            )

        batch: list[tuple[Any, Future[Any]]] = [(fn, Future()) for fn in (keep, change, load)]
        assert store._group is not None
        store._group._execute(batch)
        kept, changed, loaded = (f.result() for _, f in batch)
        assert (kept.stage, changed, loaded) == ("instructions", None, "trial")
    finally:
        store.dispose()
