"""What every study step writes besides its own rows: the step under its key and the session's
last-step time; and the step's timings."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

from sqlalchemy import bindparam, insert, update
from sqlalchemy.orm import Session

from emogen.study.tables import SessionRow, StepRow, as_utc, core_table, utcnow

#: The step's own rows: its key (idempotency) and the session's last-step time.
_INSERT_STEP = insert(core_table(StepRow))
_SESSIONS = core_table(SessionRow)
_TOUCH_SESSION = (
    update(_SESSIONS).where(_SESSIONS.c.id == bindparam("sid")).values(updated_at=bindparam("at"))
)


def record_step(ex: Session, session_id: int, kind: str, key: str, digest: str) -> datetime:
    """Record the step under its key and touch the session; returns the time."""
    now = utcnow()
    ex.execute(
        _INSERT_STEP,
        {
            "session_id": session_id,
            "key": key,
            "kind": kind,
            "request_hash": digest,
            "created_at": now,
        },
    )
    ex.execute(_TOUCH_SESSION, {"sid": session_id, "at": now})
    return now


def elapsed_ms(later: datetime, earlier: datetime | None) -> float:
    """Milliseconds from ``earlier`` to ``later`` (0 when there is no earlier time)."""
    e = as_utc(earlier)
    later_utc = as_utc(later)
    if e is None or later_utc is None:
        return 0.0
    return max(0.0, (later_utc - e).total_seconds() * 1000.0)


@dataclass(frozen=True)
class Timing:
    """What the page reports of a step: ``response_ms`` (faces visible → answer) and
    ``load_ms`` (population received → faces drawn: for generation 0 the page, model and
    texture loading). The server's time excludes ``load_ms``: see :func:`server_ms`."""

    response_ms: float | None = None
    load_ms: float | None = None


def server_ms(later: datetime, shown_at: datetime | None, load_ms: float | None) -> float:
    """``server_response_ms``: from the population stored to the answer received, less the
    page's reported loading time (so generation 0 does not count page and model loading)."""
    return max(0.0, elapsed_ms(later, shown_at) - (load_ms or 0.0))
