"""What the researcher dashboard shows beside the sessions: durations, progress per condition,
Latin-square row counts, and the study's estimated session length.

Everything is counted over the study rows of the served design (``StudyContext.accepted``: a
config that changed only its texts counts with its earlier versions). Durations are from consent
to completion (a completed session) or to the last step (one still running); the export's
``sessions`` table has the same times (``consented_at``, ``completed_at``).
"""

from __future__ import annotations

import statistics
from datetime import datetime
from typing import Any

from sqlalchemy import func, select

from emogen.study.check import check_launch
from emogen.study.config import StudyConfig
from emogen.study.design import balanced_latin_square
from emogen.study.length import session_length
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, TrialRow
from emogen.tasks.registry import task_named


def seconds_between(start: datetime | None, end: datetime | None) -> float | None:
    """Seconds from ``start`` to ``end`` (None when either is missing)."""
    if start is None or end is None:
        return None
    return (end - start).total_seconds()


def durations(store: Store, study_ids: tuple[int, ...]) -> dict[str, Any]:
    """Completed sessions' durations (consent → completion), in minutes: n, median, quartiles."""
    with store.read() as db:
        rows = db.execute(
            select(SessionRow.consented_at, SessionRow.completed_at).where(
                SessionRow.study_id.in_(study_ids), SessionRow.completed_at.is_not(None)
            )
        ).all()
    minutes = sorted(
        s / 60 for s in (seconds_between(a, b) for a, b in rows) if s is not None and s >= 0
    )
    out: dict[str, Any] = {"completed": len(minutes), "median_min": None, "quartiles_min": None}
    if minutes:
        out["median_min"] = round(statistics.median(minutes), 2)
        if len(minutes) >= 2:
            q = statistics.quantiles(minutes, n=4, method="inclusive")
            out["quartiles_min"] = [round(q[0], 2), round(q[2], 2)]
    return out


def condition_progress(store: Store, study_ids: tuple[int, ...]) -> list[dict[str, Any]]:
    """Per condition (block, task, emotion, identity): trials assigned, started and done over
    the study's sessions (a block whose trials are not the design's counterbalanced
    conditions, e.g. faces to label, counts as one condition)."""
    columns = (TrialRow.block, TrialRow.task, TrialRow.emotion, TrialRow.identity)
    with store.read() as db:
        rows = db.execute(
            select(*columns, TrialRow.status, func.count())
            .join(SessionRow, TrialRow.session_id == SessionRow.id)
            .where(SessionRow.study_id.in_(study_ids))
            .group_by(*columns, TrialRow.status)
        ).all()
    table: dict[tuple[int, str, str, str], dict[str, Any]] = {}
    for block, task, emotion, identity, status, n in rows:
        key = (int(block), str(task), str(emotion or ""), str(identity or ""))
        if not task_named(str(task)).block.counterbalanced:
            key = (int(block), str(task), "", "")
        line = table.setdefault(key, _line(key))
        line["assigned"] += int(n)
        if status == "done":
            line["done"] += int(n)
        if status != "pending":
            line["started"] += int(n)
    return [table[k] for k in sorted(table)]


def _line(key: tuple[int, str, str, str]) -> dict[str, Any]:
    names = ("block", "task", "emotion", "identity")
    return {**dict(zip(names, key, strict=True)), "assigned": 0, "started": 0, "done": 0}


def in_config_order(lines: list[dict[str, Any]], config: StudyConfig) -> list[dict[str, Any]]:
    """Condition lines in the config's order (block, then emotion, then identity)."""
    rank = {(c.block, c.emotion, c.identity): k for k, c in enumerate(config.conditions())}

    def place(x: dict[str, Any]) -> tuple[int, int]:
        return x["block"], rank.get((x["block"], x["emotion"], x["identity"]), len(rank))

    return sorted(lines, key=place)


def row_counts(store: Store, config: StudyConfig, study_ids: tuple[int, ...]) -> dict[str, Any]:
    """Latin-square rows of the first counterbalanced block: how many sessions (and completed
    ones) got each row, every row listed (``rows``: None when the study does not use a Latin
    square)."""
    balanced = [(k, b) for k, b in enumerate(config.study_blocks()) if b.counterbalanced]
    if not balanced or balanced[0][1].order != "latin_square":
        order = balanced[0][1].order if balanced else None
        return {"order": order, "counterbalance": None, "rows": None}
    n_trials = sum(1 for c in config.conditions() if c.block == balanced[0][0])
    n_rows = len(balanced_latin_square(n_trials))
    with store.read() as db:
        rows = db.execute(
            select(SessionRow.order_row, SessionRow.stage, func.count())
            .where(SessionRow.study_id.in_(study_ids), SessionRow.order_kind == "latin_square")
            .group_by(SessionRow.order_row, SessionRow.stage)
        ).all()
    counts = [{"row": r, "sessions": 0, "done": 0} for r in range(n_rows)]
    for row, stage, n in rows:
        if 0 <= int(row) < n_rows:
            counts[int(row)]["sessions"] += int(n)
            counts[int(row)]["done"] += int(n) if stage == "done" else 0
    return {"order": "latin_square", "counterbalance": config.counterbalance, "rows": counts}


def block_orders(
    store: Store, config: StudyConfig, study_ids: tuple[int, ...]
) -> list[dict[str, Any]]:
    """Sessions (and completed ones) per block order shown, by block names (``a>b>c``): read
    from the trials' positions, as the export's ``sessions.block_order``; empty when the study
    keeps its blocks in config order."""
    if config.block_order == "fixed":
        return []
    names = [b.name or f"block{k + 1}" for k, b in enumerate(config.study_blocks())]
    first = func.min(TrialRow.position)
    with store.read() as db:
        rows = db.execute(
            select(TrialRow.session_id, TrialRow.block, first, SessionRow.stage)
            .join(SessionRow, TrialRow.session_id == SessionRow.id)
            .where(SessionRow.study_id.in_(study_ids))
            .group_by(TrialRow.session_id, TrialRow.block, SessionRow.stage)
        ).all()
    shown: dict[int, list[tuple[int, int]]] = {}
    stage: dict[int, str] = {}
    for sid, block, pos, st in rows:
        shown.setdefault(int(sid), []).append((int(pos), int(block)))
        stage[int(sid)] = str(st)
    counts: dict[str, dict[str, Any]] = {}
    for sid, blocks in shown.items():
        order = ">".join(names[b] if b < len(names) else f"block{b + 1}" for _, b in sorted(blocks))
        line = counts.setdefault(order, {"order": order, "sessions": 0, "done": 0})
        line["sessions"] += 1
        line["done"] += int(stage[sid] == "done")
    return [counts[k] for k in sorted(counts)]


def design_notes(config: StudyConfig) -> list[str]:
    """What the design lets a launch expect (``emogen study check``'s launch warnings: the
    expected share of fallback faces), beside what :func:`block_notes` finds so far."""
    return [f"expected ({f.where}): {f.message}" for f in check_launch(config)]


def block_notes(store: Store, config: StudyConfig, study_ids: tuple[int, ...]) -> list[str]:
    """What each block's task says needs the researcher's eye (:meth:`Task.notes`)."""
    sessions = select(SessionRow.id).where(SessionRow.study_id.in_(study_ids))
    with store.read() as db:
        return [
            note
            for k, block in enumerate(config.study_blocks())
            for note in task_named(block.task).notes(db, sessions, k, block)
        ]


def overview(store: Store, config: StudyConfig, study_ids: tuple[int, ...]) -> dict[str, Any]:
    """The dashboard's figures for the study rows ``study_ids`` of ``config``'s design."""
    length = session_length(config.conditions(), config.ga.generations)
    return {
        "estimate": {"minutes": list(length.minutes), "basis": length.basis()},
        "durations": durations(store, study_ids),
        "conditions": in_config_order(condition_progress(store, study_ids), config),
        "counterbalancing": row_counts(store, config, study_ids),
        "block_orders": block_orders(store, config, study_ids),
    }
