"""Token buckets kept in the study database, shared by every worker process (and every server)
on it: the wrong-researcher-token limit, which a per-process bucket would multiply by the
number of workers (with 2 workers a brute force got twice the guesses, and the right token got
through on the worker whose bucket was still full).

A bucket holds at most ``burst`` tokens and gains ``per_minute / 60`` a second (wall-clock
time: the processes share no monotonic clock); a failure takes one. Full buckets are forgotten,
so the table holds only the addresses that failed recently.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from sqlalchemy import delete, select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from emogen.study.storage import Store
from emogen.study.tables import ResearcherFailureRow


class SharedBuckets:
    """Per-client token buckets in the ``researcher_failures`` table (``wait`` / ``take`` as
    the web layer's in-process buckets)."""

    def __init__(
        self,
        store: Store,
        *,
        burst: int,
        per_minute: float,
        clock: Callable[[], float] = time.time,
    ) -> None:
        self.store = store
        self.burst = burst
        self.per_minute = per_minute
        self.clock = clock

    @property
    def enabled(self) -> bool:
        return self.per_minute > 0

    def _level(self, row: ResearcherFailureRow | None, now: float) -> float:
        if row is None:
            return float(self.burst)
        refill = max(0.0, now - row.updated) * self.per_minute / 60
        return min(float(self.burst), row.tokens + refill)

    def _wait_for(self, tokens: float) -> float:
        return 0.0 if tokens >= 1 else (1 - tokens) * 60 / self.per_minute

    def wait(self, key: str) -> float:
        """Seconds until ``key`` may try again (0: now), taking nothing."""
        if not self.enabled:
            return 0.0
        with self.store.read() as db:
            row = db.get(ResearcherFailureRow, key[:64])
            return self._wait_for(self._level(row, self.clock()))

    def take(self, key: str) -> float:
        """A failure of ``key``: a token taken; 0 when it had one, else the seconds until."""
        if not self.enabled:
            return 0.0

        def work(db: Session) -> float:
            now = self.clock()
            row = db.scalar(
                select(ResearcherFailureRow)
                .where(ResearcherFailureRow.client == key[:64])
                .with_for_update()
            )
            tokens = self._level(row, now)
            left = tokens - 1 if tokens >= 1 else tokens
            if row is None:
                db.add(ResearcherFailureRow(client=key[:64], tokens=left, updated=now))
            else:
                row.tokens, row.updated = left, now
            full_after = self.burst * 60 / self.per_minute
            db.execute(
                delete(ResearcherFailureRow).where(ResearcherFailureRow.updated < now - full_after)
            )
            return 0.0 if tokens >= 1 else self._wait_for(tokens)

        for _ in range(3):
            try:
                return self.store.transact(work)
            except IntegrityError:  # two first failures of one address at once
                continue
        return self._wait_for(0.0)
