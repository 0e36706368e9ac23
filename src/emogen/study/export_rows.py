"""The rows of the export tables, one function per table, from the records of a read.

:func:`load_records` reads the sessions (and everything under them) of some studies;
each ``*_rows`` function turns them into the tidy rows of one table (see :mod:`emogen.study.export`).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from emogen.ga.state import collision_solver_of_state, stream_of_state
from emogen.study.tables import SCHEMA_VERSION, SessionRow, StudyRow, TrialRow, as_utc
from emogen.tasks.categorise.tables import ResponseRow, StimulusRow
from emogen.tasks.evolve.tables import FaceRow, PopulationRow, RatingRow, RestartRow, SelectionRow

Row = dict[str, Any]

#: Each table's columns (``faces`` adds ``g_<gene>`` and ``w_<weight>`` columns, ``identities``
#: the appearance parameters; every table ends with the record stamp).
TABLE_COLUMNS = {
    "sessions": ["study", "session_id", "participant_id", "participant_source", "session_number",
                 "seed", "order_kind", "order_row", "stage", "n_trials", "user_agent",
                 "created_at", "consented_at", "started_at", "completed_at"],
    "trials": ["study", "session_id", "participant_id", "participant_source", "trial", "block",
               "block_name", "task", "condition", "emotion",
               "identity", "repetition", "seed", "ga_stream", "collision_solver", "status", "attempts",
               "generation_reached", "final_face_id", "started_at", "finished_at"],
    "faces": ["study", "session_id", "participant_id", "participant_source", "trial", "attempt", "generation",
              "position", "face_id", "parent_a", "parent_b", "operator", "shown_at"],
    "selections": ["study", "session_id", "participant_id", "participant_source", "trial", "attempt", "generation",
                   "face_id", "role", "rank", "n_selected", "shown_at", "submitted_at",
                   "server_response_ms", "load_ms", "client_response_ms", "step_key"],
    "restarts": ["study", "session_id", "participant_id", "participant_source", "trial", "attempt", "generation",
                 "shown_at", "submitted_at", "server_response_ms", "load_ms",
                 "client_response_ms", "step_key"],
    "ratings": ["study", "session_id", "participant_id", "participant_source", "trial", "emotion", "identity",
                "face_id", "value", "points", "submitted_at", "server_response_ms",
                "client_response_ms", "step_key"],
    "responses": ["study", "session_id", "participant_id", "participant_source", "trial",
                  "block", "block_name", "source", "fallback", "source_session_id",
                  "source_participant_id", "source_trial", "source_face_id", "source_row",
                  "source_label", "intended", "identity", "labels", "label", "label_position",
                  "correct", "intensity", "confidence", "shown_at", "submitted_at",
                  "server_response_ms", "load_ms", "client_response_ms", "step_key"],
    "identities": ["study", "identity", "shape", "shape_coefficients"],
    "study": ["study", "config_json", "model_name", "gene_names", "weight_names", "framing",
              "created_at"],
}  # fmt: skip


def iso(t: datetime | None) -> str | None:
    u = as_utc(t)
    return None if u is None else u.isoformat()


@dataclass
class Records:
    """The rows read for an export, and lookups by id."""

    studies: dict[int, StudyRow]
    sessions: list[SessionRow]
    trials: list[TrialRow]
    populations: list[PopulationRow]
    faces: list[FaceRow]
    selections: list[SelectionRow]
    restarts: list[RestartRow]
    ratings: list[RatingRow]
    stimuli: list[StimulusRow] = field(default_factory=list)
    responses: list[ResponseRow] = field(default_factory=list)
    #: participant ids of the sessions others' faces came from (any session of the study)
    participants: dict[int, str] = field(default_factory=dict)
    by_session: dict[int, SessionRow] = field(init=False)
    by_trial: dict[int, TrialRow] = field(init=False)
    by_population: dict[int, PopulationRow] = field(init=False)
    _corrects: dict[int, bool] = field(init=False, default_factory=dict)
    _block_names: dict[int, list[str]] = field(init=False, default_factory=dict)

    def __post_init__(self) -> None:
        self.by_session = {s.id: s for s in self.sessions}
        self.by_trial = {t.id: t for t in self.trials}
        self.by_population = {p.id: p for p in self.populations}

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

    def corrects(self, trial: TrialRow) -> bool:
        """Whether the trial's study corrects its faces (``correct`` in its config)."""
        st = self.studies[self.by_session[trial.session_id].study_id]
        if st.id not in self._corrects:
            self._corrects[st.id] = bool(json.loads(st.config_json).get("correct", True))
        return self._corrects[st.id]

    def trial_stamp(self, trial: TrialRow) -> Row:
        return self.stamp(self.by_session[trial.session_id])


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
    tids = [t.id for t in trials]
    pops = list(
        db.scalars(
            select(PopulationRow).where(PopulationRow.trial_id.in_(tids)).order_by(PopulationRow.id)
        )
    )
    pids = [p.id for p in pops]
    faces = list(
        db.scalars(
            select(FaceRow)
            .where(FaceRow.population_id.in_(pids))
            .order_by(FaceRow.population_id, FaceRow.position)
        )
    )
    selections = list(db.scalars(select(SelectionRow).where(SelectionRow.population_id.in_(pids))))
    restarts = list(db.scalars(select(RestartRow).where(RestartRow.population_id.in_(pids))))
    ratings = list(db.scalars(select(RatingRow).where(RatingRow.trial_id.in_(tids))))
    stimuli = list(
        db.scalars(
            select(StimulusRow).where(StimulusRow.trial_id.in_(tids)).order_by(StimulusRow.trial_id)
        )
    )
    responses = list(db.scalars(select(ResponseRow).where(ResponseRow.trial_id.in_(tids))))
    sources = {s.source_session_id for s in stimuli if s.source_session_id is not None}
    query = select(SessionRow.id, SessionRow.participant_id).where(SessionRow.id.in_(sources))
    participants = {int(i): str(p) for i, p in db.execute(query)}
    return Records(studies, sessions, trials, pops, faces, selections, restarts, ratings,
                   stimuli, responses, participants)  # fmt: skip


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
        yield {
            **rec.key(t),
            "block": t.block,
            "block_name": rec.block_name(t),
            "task": t.task,
            "condition": t.condition,
            "emotion": t.emotion or None,  # a categorise face of unknown making: NA
            "identity": t.identity,
            "repetition": t.repetition,
            "seed": t.seed,
            "ga_stream": stream_of_state(t.engine_state) if t.engine_state else None,
            "collision_solver": (
                collision_solver_of_state(t.engine_state)
                if t.engine_state and rec.corrects(t)
                else None
            ),
            "status": t.status,
            "attempts": t.attempt + 1,
            "generation_reached": t.generation,
            "final_face_id": t.final_face_id,
            "started_at": iso(t.started_at),
            "finished_at": iso(t.finished_at),
            **rec.trial_stamp(t),
        }


def face_rows(rec: Records) -> Iterator[Row]:
    gene_cols = {sid: json.loads(st.gene_names) for sid, st in rec.studies.items()}
    weight_cols = {sid: json.loads(st.weight_names) for sid, st in rec.studies.items()}
    for f in rec.faces:
        p = rec.by_population[f.population_id]
        t = rec.by_trial[p.trial_id]
        s = rec.by_session[t.session_id]
        row: Row = {
            **rec.key(t),
            "attempt": p.attempt,
            "generation": p.generation,
            "position": f.position,
            "face_id": f.face_id,
            "parent_a": None if f.parent_a < 0 else f.parent_a,
            "parent_b": None if f.parent_b < 0 else f.parent_b,
            "operator": f.operator,
            "shown_at": iso(p.shown_at),
        }
        row.update(zip((f"g_{n}" for n in gene_cols[s.study_id]), json.loads(f.genes), strict=True))
        row.update(
            zip((f"w_{n}" for n in weight_cols[s.study_id]), json.loads(f.weights), strict=True)
        )
        row.update(rec.stamp(s))
        yield row


def selection_rows(rec: Records) -> Iterator[Row]:
    for sel in sorted(rec.selections, key=lambda x: x.id):
        p = rec.by_population[sel.population_id]
        t = rec.by_trial[p.trial_id]
        others = json.loads(sel.other_face_ids)
        chosen = [(sel.elite_face_id, "elite")] + [(o, "other") for o in others]
        for rank, (face, role) in enumerate(chosen):
            yield {
                **rec.key(t),
                "attempt": p.attempt,
                "generation": p.generation,
                "face_id": face,
                "role": role,
                "rank": rank,
                "n_selected": 1 + len(others),
                "shown_at": iso(p.shown_at),
                "submitted_at": iso(sel.submitted_at),
                "server_response_ms": sel.server_response_ms,
                "load_ms": sel.load_ms,
                "client_response_ms": sel.client_response_ms,
                "step_key": sel.step_key,
                **rec.trial_stamp(t),
            }


def restart_rows(rec: Records) -> Iterator[Row]:
    for r in sorted(rec.restarts, key=lambda x: x.id):
        p = rec.by_population[r.population_id]
        t = rec.by_trial[p.trial_id]
        yield {
            **rec.key(t),
            "attempt": p.attempt,
            "generation": p.generation,
            "shown_at": iso(p.shown_at),
            "submitted_at": iso(r.submitted_at),
            "server_response_ms": r.server_response_ms,
            "load_ms": r.load_ms,
            "client_response_ms": r.client_response_ms,
            "step_key": r.step_key,
            **rec.trial_stamp(t),
        }


def rating_rows(rec: Records) -> Iterator[Row]:
    for rt in sorted(rec.ratings, key=lambda x: x.id):
        t = rec.by_trial[rt.trial_id]
        yield {
            **rec.key(t),
            "emotion": t.emotion,
            "identity": t.identity,
            "face_id": rt.face_id,
            "value": rt.value,
            "points": rt.points,
            "submitted_at": iso(rt.submitted_at),
            "server_response_ms": rt.server_response_ms,
            "client_response_ms": rt.client_response_ms,
            "step_key": rt.step_key,
            **rec.trial_stamp(t),
        }


def response_rows(rec: Records) -> Iterator[Row]:
    """One row per categorise trial whose face was drawn: the face (source, identity, genes
    and full weights), the labels offered in their order, the answer (NA until answered)."""
    gene_cols = {sid: json.loads(st.gene_names) for sid, st in rec.studies.items()}
    weight_cols = {sid: json.loads(st.weight_names) for sid, st in rec.studies.items()}
    answers = {r.trial_id: r for r in rec.responses}
    for stim in rec.stimuli:  # in trial id order: sessions, then positions
        t = rec.by_trial[stim.trial_id]
        s = rec.by_session[t.session_id]
        r = answers.get(t.id)
        label = None if r is None else r.label
        row: Row = {
            **rec.key(t),
            "block": t.block,
            "block_name": rec.block_name(t),
            "source": stim.source,
            "fallback": bool(stim.fallback),
            "source_session_id": stim.source_session_id,
            "source_participant_id": rec.participants.get(stim.source_session_id or -1),
            "source_trial": stim.source_trial,
            "source_face_id": stim.source_face_id,
            "source_row": stim.source_row,
            "source_label": stim.source_label,
            "intended": stim.intended,
            "identity": stim.identity,
            "labels": "|".join(json.loads(stim.labels)),
            "label": label,
            "label_position": None if r is None else r.label_position,
            "correct": None if r is None or stim.intended is None else label == stim.intended,
            "intensity": None if r is None else r.intensity,
            "confidence": None if r is None else r.confidence,
            "shown_at": iso(stim.shown_at),
            "submitted_at": None if r is None else iso(r.submitted_at),
            "server_response_ms": None if r is None else r.server_response_ms,
            "load_ms": None if r is None else r.load_ms,
            "client_response_ms": None if r is None else r.client_response_ms,
            "step_key": None if r is None else r.step_key,
        }
        genes = json.loads(stim.genes) if stim.genes else [None] * len(gene_cols[s.study_id])
        row.update(zip((f"g_{n}" for n in gene_cols[s.study_id]), genes, strict=True))
        row.update(
            zip((f"w_{n}" for n in weight_cols[s.study_id]), json.loads(stim.weights), strict=True)
        )
        row.update(rec.stamp(s))
        yield row


#: The per-session tables and the function that makes each one's rows from the records.
SESSION_TABLE_ROWS: dict[str, Callable[[Records], Iterator[Row]]] = {
    "sessions": session_rows,
    "trials": trial_rows,
    "faces": face_rows,
    "selections": selection_rows,
    "restarts": restart_rows,
    "ratings": rating_rows,
    "responses": response_rows,
}
