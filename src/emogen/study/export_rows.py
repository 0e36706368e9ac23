"""The records of an export read, and the study's own per-session tables (``sessions``,
``trials``); each task's tables are in its own package (``emogen.tasks.<task>.export``).

:func:`load_records` reads the sessions (and everything under them) of some studies; each
table's ``rows`` function turns them into the tidy rows of one table (see
:mod:`emogen.study.export`).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from emogen.study.retest import retest_links
from emogen.study.tables import SCHEMA_VERSION, SessionRow, StudyRow, TrialRow, core_table
from emogen.tasks.export import TRIAL_KEY, ExportTable, Row, iso, typed_columns
from emogen.tasks.registry import TASKS, task_named

__all__ = ["Records", "iso", "load_records"]


@dataclass
class Records:
    """The rows read for an export, and lookups by id."""

    studies: dict[int, StudyRow]
    sessions: list[SessionRow]
    trials: list[TrialRow]
    #: every registered task's records under these trials, by record type (in trial, then
    #: record order)
    records: dict[type, list[Any]] = field(default_factory=dict)
    #: participant ids of the studies' sessions (a face another participant made names its)
    participants: dict[int, str] = field(default_factory=dict)
    by_session: dict[int, SessionRow] = field(init=False)
    by_trial: dict[int, TrialRow] = field(init=False)
    _by_id: dict[type, dict[int, Any]] = field(init=False, default_factory=dict)
    _corrects: dict[int, bool] = field(init=False, default_factory=dict)
    _block_names: dict[int, list[str]] = field(init=False, default_factory=dict)
    _trials_of: dict[int, list[TrialRow]] = field(init=False, default_factory=dict)
    #: a retest session's first session, by the retest session's id (emogen.study.retest)
    retests: dict[int, int] = field(init=False, default_factory=dict)
    _face_columns: dict[int, tuple[list[str], list[str]]] = field(init=False, default_factory=dict)

    def __post_init__(self) -> None:
        self.by_session = {s.id: s for s in self.sessions}
        self.by_trial = {t.id: t for t in self.trials}

    def rows_of(self, row: type) -> list[Any]:
        """The records of one type (a task's row class)."""
        return self.records.get(row, [])

    def by_id(self, row: type) -> dict[int, Any]:
        """The records of one type by their id."""
        if row not in self._by_id:
            self._by_id[row] = {r.id: r for r in self.rows_of(row)}
        return self._by_id[row]

    def face_values(self, session: SessionRow, genes: str | None, weights: str) -> Row:
        """A face's ``g_<gene>`` (NA when ``genes`` is None: a file face) and ``w_<weight>``
        cells, from their stored JSON lists."""
        gene_cols, weight_cols = self.face_columns(session)
        values = json.loads(genes) if genes else [None] * len(gene_cols)
        row = dict(zip(gene_cols, values, strict=True))
        row.update(zip(weight_cols, json.loads(weights), strict=True))
        return row

    def stamp(self, session: SessionRow) -> Row:
        """The record stamp of every row: schema, package version, model and config hashes."""
        st = self.studies[session.study_id]
        return {
            "schema_version": SCHEMA_VERSION,
            "package_version": session.package_version,
            "model_hash": st.model_hash,
            "study_config_hash": st.config_hash,
        }

    def key(self, trial: TrialRow) -> Row:
        """The columns that name a trial: study, session, participant, trial position."""
        s = self.by_session[trial.session_id]
        return {
            "study": self.studies[s.study_id].name,
            "session_id": s.id,
            "participant_id": s.participant_id,
            "participant_source": s.participant_source,
            "trial": trial.position,
        }

    def block_name(self, trial: TrialRow) -> str:
        """The trial's block's name (its ``name`` in the config, else ``block<k>`` from 1)."""
        st = self.studies[self.by_session[trial.session_id].study_id]
        if st.id not in self._block_names:
            blocks = json.loads(st.config_json).get("blocks") or [{}]
            self._block_names[st.id] = [
                b.get("name") or f"block{k + 1}" for k, b in enumerate(blocks)
            ]
        names = self._block_names[st.id]
        return names[trial.block] if trial.block < len(names) else f"block{trial.block + 1}"

    def block_order(self, session: SessionRow) -> str | None:
        """The session's blocks in the order shown, by name (``make_male>make_female>…``), read
        from its trials' positions (None: no trials)."""
        shown: dict[str, None] = {}
        for t in self.trials_of(session.id):
            shown.setdefault(self.block_name(t), None)
        return ">".join(shown) or None

    def trials_of(self, session_id: int) -> list[TrialRow]:
        """The session's trials in position order."""
        if not self._trials_of:
            for t in self.trials:
                self._trials_of.setdefault(t.session_id, []).append(t)
        return sorted(self._trials_of.get(session_id, []), key=lambda t: t.position)

    def corrects(self, trial: TrialRow) -> bool:
        """Whether the trial's study corrects its faces (``correct`` in its config)."""
        st = self.studies[self.by_session[trial.session_id].study_id]
        if st.id not in self._corrects:
            self._corrects[st.id] = bool(json.loads(st.config_json).get("correct", True))
        return self._corrects[st.id]

    def trial_stamp(self, trial: TrialRow) -> Row:
        return self.stamp(self.by_session[trial.session_id])

    def face_columns(self, session: SessionRow) -> tuple[list[str], list[str]]:
        """The ``g_<gene>`` and ``w_<weight>`` column names of the session's study."""
        st = self.studies[session.study_id]
        if st.id not in self._face_columns:
            self._face_columns[st.id] = (
                [f"g_{n}" for n in json.loads(st.gene_names)],
                [f"w_{n}" for n in json.loads(st.weight_names)],
            )
        return self._face_columns[st.id]


def load_records(
    db: Session, studies: dict[int, StudyRow], session_ids: list[int] | None
) -> Records:
    """The sessions of these studies (only ``session_ids`` if given) and all rows under them."""
    q = select(SessionRow).where(SessionRow.study_id.in_(list(studies))).order_by(SessionRow.id)
    if session_ids is not None:
        q = q.where(SessionRow.id.in_(session_ids))
    sessions = list(db.scalars(q))
    sids = [s.id for s in sessions]
    trials = list(
        db.scalars(
            select(TrialRow)
            .where(TrialRow.session_id.in_(sids))
            .order_by(TrialRow.session_id, TrialRow.position)
        )
    )
    sources = select(SessionRow.id, SessionRow.participant_id).where(
        SessionRow.study_id.in_(list(studies))
    )
    participants = {int(i): str(p) for i, p in db.execute(sources)}
    records = task_records(db, [t.id for t in trials])
    out = Records(studies, sessions, trials, records, participants)
    out.retests = retest_links(db, studies, sessions)
    return out


def task_records(db: Session, trial_ids: list[int]) -> dict[type, list[Any]]:
    """Every registered task's records under these trials: a table with a ``trial_id`` by it
    (in trial, then record order); a table under another task table (a population's faces) by
    its key to that table's records (in parent, then record order)."""
    out: dict[type, list[Any]] = {}
    ids: dict[str, list[int]] = {"trials": trial_ids}
    pending: list[Any] = [row for task in TASKS.values() for row in task.tables]
    while pending:
        row = next((r for r in pending if _parent(r, ids) is not None), None)
        if row is None:  # pragma: no cover - a task table under no trial
            raise ValueError(f"task tables {[r.__name__ for r in pending]} hang from no trial")
        pending.remove(row)
        parent, column = _parent(row, ids)  # type: ignore[misc]
        key = getattr(row, column)
        table = core_table(row)
        query = select(row).where(key.in_(ids[parent])).order_by(key, table.c.id)
        found: list[Any] = list(db.scalars(query))
        out[row] = found
        ids[table.name] = [r.id for r in found]
    return out


def _parent(row: Any, loaded: dict[str, list[int]]) -> tuple[str, str] | None:
    """(the loaded table a task table hangs from, its column) — ``trials`` first."""
    keys = [(fk.column.table.name, fk.parent.name) for fk in core_table(row).foreign_keys]
    for table, column in sorted(keys, key=lambda k: k[0] != "trials"):
        if table in loaded:
            return table, column
    return None


def session_rows(rec: Records) -> Iterator[Row]:
    for s in rec.sessions:
        yield {
            "study": rec.studies[s.study_id].name,
            "session_id": s.id,
            "participant_id": s.participant_id,
            "participant_source": s.participant_source,
            "session_number": s.number,
            "seed": s.seed,
            "order_kind": s.order_kind,
            "order_row": None if s.order_row < 0 else s.order_row,
            "block_order": rec.block_order(s),
            "retest_of_session_id": rec.retests.get(s.id),
            "stage": s.stage,
            "n_trials": len(json.loads(s.trial_order)),
            "user_agent": s.user_agent,
            "created_at": iso(s.created_at),
            "consented_at": iso(s.consented_at),
            "started_at": iso(s.started_at),
            "completed_at": iso(s.completed_at),
            **rec.stamp(s),
        }


def trial_rows(rec: Records) -> Iterator[Row]:
    for t in rec.trials:
        makes = task_named(t.task).block.makes_faces  # its emotion and face are its own
        yield {
            **rec.key(t),
            "block": t.block,
            "block_name": rec.block_name(t),
            "task": t.task,
            "condition": t.condition,
            # a face-making trial: the emotion to make; other tasks' own tables say what they
            # showed
            "emotion": (t.emotion or None) if makes else None,
            "identity": t.identity,
            "repetition": t.repetition,
            "seed": t.seed,
            **_state_facts(t, rec.corrects(t)),
            "status": t.status,
            "attempts": t.attempt + 1,
            "generation_reached": t.generation,
            "final_face_id": t.final_face_id if makes else None,
            "started_at": iso(t.started_at),
            "finished_at": iso(t.finished_at),
            **rec.trial_stamp(t),
        }


SESSIONS = ExportTable(
    "sessions",
    typed_columns(
        "study:str session_id:int participant_id:str participant_source:str session_number:int "
        "seed:seed order_kind:str order_row:int block_order:str retest_of_session_id:int stage:str n_trials:int user_agent:str "
        "created_at:time consented_at:time started_at:time completed_at:time"
    ),
    session_rows,
)
TRIALS = ExportTable(
    "trials",
    TRIAL_KEY
    + typed_columns(
        "block:int block_name:str task:str condition:int emotion:str identity:str repetition:int "
        "seed:seed ga_stream:int collision_solver:int status:str attempts:int "
        "generation_reached:int final_face_id:int started_at:time finished_at:time"
    ),
    trial_rows,
)


def _state_facts(t: TrialRow, corrects: bool) -> dict[str, Any]:
    """What the trial's task reads from its stored state for the trials table (the GA's stream
    and, where faces are corrected, its collision solver); missing for other tasks."""
    facts = task_named(t.task).state_facts(t.engine_state)
    return {
        "ga_stream": facts.get("ga_stream"),
        "collision_solver": facts.get("collision_solver") if corrects else None,
    }
