"""Participant sessions: the study's steps, each one transaction committed before it is answered.

A session goes consent (its creation) → instructions → trial 1 … T → done. In a trial the GA
engine shows generations 0 … G; every shown population (genes, full weights, face ids, parent
ids, operators) is stored when it is made, every selection / restart / rating with its
timestamps and response times. The engine's JSON state is kept with the trial, so a reload or a
server restart resumes exactly where the participant was.

Every state-changing step carries an idempotency key: the same key again returns the current
state without doing anything (a double click, a retried request); a key reused for a different
request, or a request for a generation that is no longer shown, is a conflict (HTTP 409).
"""

from __future__ import annotations

import hashlib
import json
import re
import secrets
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING, Any

import numpy as np
from sqlalchemy import func, insert, select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session, selectinload

from emogen import __version__
from emogen.errors import ConfigError, SelectionError
from emogen.ga.engine import Corrector, Engine, Population, correctives_of
from emogen.model.rig import Rig
from emogen.rng import fresh_seed, spawn_seeds
from emogen.study.config import StudyConfig, check_identities
from emogen.study.design import trial_order
from emogen.study.errors import SessionNotFound, StepConflict
from emogen.study.storage import (
    FaceRow,
    PopulationRow,
    RatingRow,
    RestartRow,
    SelectionRow,
    SessionRow,
    StepRow,
    Store,
    StudyRow,
    TrialRow,
    as_utc,
    dumps,
    utcnow,
)

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

PARTICIPANT_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._:@+-]{0,127}$")


def _correctives(population: Population) -> tuple[list[str], np.ndarray] | None:
    """Corrective columns a population carries, if the engine corrects faces.

    Either ``population.correction`` (an ``emogen.correct`` CorrectionResult: combinational then
    collision weights) or ``population.correctives`` (n_faces, C) with ``corrective_names``.
    """
    correction = getattr(population, "correction", None)
    if correction is not None:
        names = [*correction.combinational_names, *correction.collision_names]
        values = np.hstack([correction.combinational, correction.collision])
        return names, np.asarray(values, dtype=np.float64).reshape(len(population), -1)
    extra = getattr(population, "correctives", None)
    if extra is None:
        return None
    values = np.asarray(extra, dtype=np.float64).reshape(len(population), -1)
    given = getattr(population, "corrective_names", None)
    names = (
        list(given) if given is not None else [f"corrective_{i}" for i in range(values.shape[1])]
    )
    return names, values


def full_weights(population: Population) -> np.ndarray:
    """(n_faces, n_columns) float: the population's full weights, then its correctives if any."""
    w = np.asarray(population.weights, dtype=np.float64)
    extra = _correctives(population)
    return w if extra is None else np.hstack([w, extra[1]])


def weight_names(population: Population, rig: Rig) -> list[str]:
    """Column names of :func:`full_weights`: the model's shapes, then the correctives."""
    extra = _correctives(population)
    return list(rig.shape_names) + ([] if extra is None else extra[0])


def _ms(later: datetime, earlier: datetime | None) -> float:
    e = as_utc(earlier)
    later_utc = as_utc(later)
    if e is None or later_utc is None:
        return 0.0
    return max(0.0, (later_utc - e).total_seconds() * 1000.0)


def request_hash(kind: str, payload: dict[str, Any]) -> str:
    text = kind + ":" + json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


@dataclass(frozen=True)
class StudyContext:
    """What a service knows of its study: the config, the rig, the study row's id."""

    config: StudyConfig
    rig: Rig
    model_name: str
    model_hash: str
    study_id: int
    gene_names: tuple[str, ...]
    weight_names: tuple[str, ...]


class StudyCorrectors:
    """One corrector per identity shape (``correctives_of`` the model with the shape of the
    study's identity of that name; identities that share a shape share it), made on first use;
    none when the study does not correct faces."""

    def __init__(self, config: StudyConfig, model: FaceModel | None) -> None:
        if config.correct and model is None:
            raise ConfigError(
                "the study corrects faces (correct = true): the server needs the face model "
                "(pass model=…), or set correct = false"
            )
        self.config = config
        self.model = model if config.correct else None
        self._made: dict[str | tuple[float, ...], Corrector] = {}

    def __call__(self, identity: str) -> Corrector | None:
        if self.model is None:
            return None
        shape = self.config.identity_of(identity).shape
        if shape not in self._made:
            m = self.model if shape == "generic" else self.model.with_identity(shape)
            self._made[shape] = correctives_of(m)
        return self._made[shape]


class StudyService:
    """The study's steps over a :class:`Store`. Methods return the participant's state (JSON).

    model : the face model, needed when the config corrects faces (``correct = true``): every
    engine then corrects its populations, and a face's stored (and shown) weights are the shape
    weights followed by the corrective weights, in the model GLB's morph-target order.
    """

    def __init__(self, config: StudyConfig, store: Store, rig: Rig, *, model_name: str,
                 model_hash: str, model: FaceModel | None = None) -> None:  # fmt: skip
        check_identities(config, rig, model)
        self.store = store
        self.correctors = StudyCorrectors(config, model)
        probe = Engine(config.ga_for("generic"), rig, 0, corrector=self.correctors("generic")).ask()
        genes = tuple(rig.gene_names(config.ga.eye_motion))
        names = tuple(weight_names(probe, rig))
        study_id = self._register(config, model_name, model_hash, genes, names)
        self.ctx = StudyContext(config, rig, model_name, model_hash, study_id, genes, names)

    # ---- study row ---------------------------------------------------------------------
    def _register(
        self,
        config: StudyConfig,
        model_name: str,
        model_hash: str,
        genes: tuple[str, ...],
        names: tuple[str, ...],
    ) -> int:
        chash = config.config_hash()
        for _ in range(2):
            try:
                with self.store.write() as db:
                    row = db.scalar(
                        select(StudyRow).where(
                            StudyRow.name == config.name, StudyRow.config_hash == chash
                        )
                    )
                    if row is None:
                        row = StudyRow(
                            name=config.name,
                            config_hash=chash,
                            config_json=config.canonical_json(),
                            model_name=model_name[:128],
                            model_hash=model_hash,
                            gene_names=dumps(list(genes)),
                            weight_names=dumps(list(names)),
                            package_version=__version__,
                            created_at=utcnow(),
                        )
                        db.add(row)
                        db.flush()
                    elif row.model_hash != model_hash:
                        raise ConfigError(
                            f"study '{config.name}' (config {chash[:12]}) was recorded with model "
                            f"{row.model_hash[:16]}…; this server loaded {model_hash[:16]}…: "
                            "serve it with the same model, or rename the study"
                        )
                    return row.id
            except IntegrityError:  # another process registered it at the same moment
                continue
        raise ConfigError(f"could not register study '{config.name}'")  # pragma: no cover

    # ---- sessions ----------------------------------------------------------------------
    def create_session(
        self,
        participant_id: str | None = None,
        *,
        resume_token: str | None = None,
        user_agent: str = "",
    ) -> tuple[str, dict[str, Any]]:
        """Consent given: a new session (token, state), or the participant's own one again.

        A participant id that already has a session is resumed only with that session's token
        (``resume_token``, kept by the participant's browser); otherwise it is a conflict.
        """
        cfg = self.ctx.config
        source = "url"
        if participant_id is None or participant_id == "":
            participant_id = "anon-" + secrets.token_hex(8)
            source = "generated"
        elif not PARTICIPANT_ID.match(participant_id):
            raise ConfigError(
                f"participant id must be 1-128 letters, digits or ._:@+- (starting with a letter "
                f"or digit); got {participant_id[:40]!r}"
            )

        def work(db: Session) -> tuple[str, dict[str, Any]]:
            study = db.get(StudyRow, self.ctx.study_id, with_for_update=True)
            existing = db.scalar(
                select(SessionRow).where(
                    SessionRow.study_id == self.ctx.study_id,
                    SessionRow.participant_id == participant_id,
                )
            )
            if existing is not None:
                if resume_token is None or not secrets.compare_digest(existing.token, resume_token):
                    raise StepConflict(
                        f"participant '{participant_id}' already has a session in this "
                        "study; reopen the link you were given (it holds your session)"
                    )
                return existing.token, self._state(db, existing)
            del study
            number = db.scalar(
                select(func.count())
                .select_from(SessionRow)
                .where(SessionRow.study_id == self.ctx.study_id)
            )
            number = int(number or 0)
            if cfg.seed is not None:
                seed = spawn_seeds(cfg.seed, number + 1)[number]
            else:
                seed = fresh_seed()
            order_seed, *trial_seeds = spawn_seeds(seed, cfg.n_trials + 1)
            order = trial_order(cfg, session_number=number, rng=np.random.default_rng(order_seed))
            now = utcnow()
            sess = SessionRow(
                study_id=self.ctx.study_id,
                token=secrets.token_urlsafe(24),
                participant_id=participant_id,
                participant_source=source,
                number=number,
                seed=seed,
                order_kind=order.kind,
                order_row=order.row,
                trial_order=dumps(list(order.order)),
                stage="instructions",
                current_trial=0,
                package_version=__version__,
                user_agent=user_agent[:256],
                created_at=now,
                consented_at=now,
                updated_at=now,
            )
            db.add(sess)
            db.flush()
            conditions = cfg.conditions()
            for pos, cond in enumerate(order.order):
                emotion, identity, rep = conditions[cond]
                db.add(
                    TrialRow(
                        session_id=sess.id,
                        position=pos,
                        condition=cond,
                        emotion=emotion,
                        identity=identity,
                        repetition=rep,
                        seed=trial_seeds[pos],
                        status="pending",
                        attempt=0,
                        generation=0,
                    )
                )
            db.flush()
            return sess.token, self._state(db, sess)

        for _ in range(3):
            try:
                return self.store.transact(work)
            except IntegrityError:  # the same participant or session number at the same moment
                continue
        raise StepConflict("the server is busy creating sessions; please try again")

    def state(self, token: str) -> dict[str, Any]:
        with self.store.read() as db:
            return self._state(db, self._session(db, token))

    def begin(self, token: str, key: str) -> dict[str, Any]:
        """Instructions read: the first trial starts (generation 0 is made and stored)."""

        def step(db: Session, sess: SessionRow) -> None:
            if sess.stage != "instructions":
                raise StepConflict(f"the session is past the instructions (stage '{sess.stage}')")
            sess.stage = "trial"
            sess.started_at = utcnow()
            self._start_trial(db, sess, 0)

        return self._step(token, "begin", key, {}, step)

    def select(
        self,
        token: str,
        key: str,
        *,
        trial: int,
        attempt: int,
        generation: int,
        elite: int,
        others: list[int],
        response_ms: float | None = None,
    ) -> dict[str, Any]:
        """The participant's selection of the shown generation; the next one is stored."""
        payload = {
            "trial": trial,
            "attempt": attempt,
            "generation": generation,
            "elite": elite,
            "others": others,
            "response_ms": response_ms,
        }

        def step(db: Session, sess: SessionRow) -> None:
            row, pop = self._shown(db, sess, trial, attempt, generation)
            engine = self._engine(row)
            engine.tell(elite, others)
            now = utcnow()
            db.add(
                SelectionRow(
                    population_id=pop.id,
                    trial_id=row.id,
                    elite_face_id=elite,
                    other_face_ids=dumps(list(others)),
                    submitted_at=now,
                    server_response_ms=_ms(now, pop.shown_at),
                    client_response_ms=response_ms,
                    step_key=key,
                )
            )
            if engine.done:
                row.status = "rating"
                row.final_face_id = int(engine.result.ids[0])
            else:
                self._store_population(db, row, engine.ask())
            row.generation = engine.generation
            row.engine_state = engine.to_json()

        return self._step(token, "select", key, payload, step)

    def restart(
        self,
        token: str,
        key: str,
        *,
        trial: int,
        attempt: int,
        generation: int,
        response_ms: float | None = None,
    ) -> dict[str, Any]:
        """'Start again': a new attempt of the trial at generation 0 (reinitialised or kept)."""
        payload = {
            "trial": trial,
            "attempt": attempt,
            "generation": generation,
            "response_ms": response_ms,
        }

        def step(db: Session, sess: SessionRow) -> None:
            if not self.ctx.config.allow_restart:
                raise StepConflict("this study does not allow starting a trial again")
            row, pop = self._shown(db, sess, trial, attempt, generation)
            engine = self._engine(row)
            now = utcnow()
            db.add(
                RestartRow(
                    population_id=pop.id,
                    trial_id=row.id,
                    submitted_at=now,
                    server_response_ms=_ms(now, pop.shown_at),
                    client_response_ms=response_ms,
                    step_key=key,
                )
            )
            population = engine.reset()
            row.attempt = engine.trial
            row.generation = engine.generation
            self._store_population(db, row, population)
            row.engine_state = engine.to_json()

        return self._step(token, "restart", key, payload, step)

    def rate(
        self, token: str, key: str, *, trial: int, value: int, response_ms: float | None = None
    ) -> dict[str, Any]:
        """The rating of the trial's final face; then the next trial starts (or the session ends)."""
        payload = {"trial": trial, "value": value, "response_ms": response_ms}
        points = self.ctx.config.rating.points

        def step(db: Session, sess: SessionRow) -> None:
            row = self._current_trial(db, sess, trial)
            if row.status != "rating":
                raise StepConflict(
                    f"trial {trial + 1} is not waiting for a rating (it is at generation "
                    f"{row.generation}); reload the page"
                )
            if not 1 <= value <= points:
                raise SelectionError(f"rating must be an integer in [1, {points}]; got {value}")
            now = utcnow()
            last = db.scalar(
                select(SelectionRow.submitted_at)
                .where(SelectionRow.trial_id == row.id)
                .order_by(SelectionRow.id.desc())
                .limit(1)
            )
            db.add(
                RatingRow(
                    trial_id=row.id,
                    face_id=int(row.final_face_id if row.final_face_id is not None else -1),
                    value=value,
                    points=points,
                    submitted_at=now,
                    server_response_ms=_ms(now, last),
                    client_response_ms=response_ms,
                    step_key=key,
                )
            )
            row.status = "done"
            row.finished_at = now
            n_trials = len(json.loads(sess.trial_order))
            if trial + 1 < n_trials:
                sess.current_trial = trial + 1
                self._start_trial(db, sess, trial + 1)
            else:
                sess.stage = "done"
                sess.completed_at = now

        return self._step(token, "rate", key, payload, step)

    # ---- internals ---------------------------------------------------------------------
    def _session(self, db: Session, token: str, *, lock: bool = False) -> SessionRow:
        query = select(SessionRow).where(SessionRow.token == token)
        if lock:
            query = query.with_for_update()
        sess = db.scalar(query)
        if sess is None:
            raise SessionNotFound("no session with this link; check the address")
        if sess.study_id != self.ctx.study_id:
            raise StepConflict(
                "this session belongs to another version of the study config than the one the "
                "server runs now; ask the researcher"
            )
        return sess

    def _step(
        self,
        token: str,
        kind: str,
        key: str,
        payload: dict[str, Any],
        action: Any,
    ) -> dict[str, Any]:
        digest = request_hash(kind, payload)

        def work(db: Session) -> dict[str, Any]:
            sess = self._session(db, token, lock=True)
            done = db.scalar(
                select(StepRow).where(StepRow.session_id == sess.id, StepRow.key == key)
            )
            if done is not None:
                if done.kind != kind or done.request_hash != digest:
                    raise StepConflict(
                        f"step key '{key}' was already used for a different request "
                        f"({done.kind}); send a new key for a new step"
                    )
                return dict(self._state(db, sess), replayed=True)
            action(db, sess)
            now = utcnow()
            db.add(
                StepRow(session_id=sess.id, key=key, kind=kind, request_hash=digest, created_at=now)
            )
            sess.updated_at = now
            db.flush()
            return self._state(db, sess)

        return self.store.transact(work)

    def _current_trial(self, db: Session, sess: SessionRow, trial: int) -> TrialRow:
        if sess.stage != "trial":
            raise StepConflict(
                f"the session is not in a trial (stage '{sess.stage}'); reload the page"
            )
        if trial != sess.current_trial:
            raise StepConflict(
                f"this request is for trial {trial + 1}, but the session is at trial "
                f"{sess.current_trial + 1}; reload the page"
            )
        row = db.scalar(
            select(TrialRow).where(TrialRow.session_id == sess.id, TrialRow.position == trial)
        )
        if row is None:  # pragma: no cover - created with the session
            raise SessionNotFound(f"trial {trial + 1} does not exist")
        return row

    def _engine(self, row: TrialRow) -> Engine:
        """The trial's engine, restored from its stored state, with its identity's corrector."""
        return Engine.from_json(
            row.engine_state or "", self.ctx.rig, corrector=self.correctors(row.identity)
        )

    def _shown(
        self, db: Session, sess: SessionRow, trial: int, attempt: int, generation: int
    ) -> tuple[TrialRow, PopulationRow]:
        row = self._current_trial(db, sess, trial)
        if row.status != "active":
            raise StepConflict(
                f"trial {trial + 1} has no generation to select from (it is waiting for the "
                "rating); reload the page"
            )
        if (attempt, generation) != (row.attempt, row.generation):
            raise StepConflict(
                f"this request is for generation {generation} (attempt {attempt + 1}) of trial "
                f"{trial + 1}, but generation {row.generation} (attempt {row.attempt + 1}) is "
                "shown now; reload the page"
            )
        pop = db.scalar(
            select(PopulationRow).where(
                PopulationRow.trial_id == row.id,
                PopulationRow.attempt == attempt,
                PopulationRow.generation == generation,
            )
        )
        if pop is None:  # pragma: no cover - stored with the engine state
            raise StepConflict("the shown generation was not stored; reload the page")
        return row, pop

    def _start_trial(self, db: Session, sess: SessionRow, position: int) -> None:
        row = db.scalar(
            select(TrialRow).where(TrialRow.session_id == sess.id, TrialRow.position == position)
        )
        if row is None:  # pragma: no cover
            raise SessionNotFound(f"trial {position + 1} does not exist")
        engine = Engine(
            self.ctx.config.ga_for(row.identity),
            self.ctx.rig,
            row.seed,
            corrector=self.correctors(row.identity),
        )
        row.status = "active"
        row.started_at = utcnow()
        row.attempt = engine.trial
        row.generation = engine.generation
        self._store_population(db, row, engine.ask())
        row.engine_state = engine.to_json()

    def _store_population(self, db: Session, trial: TrialRow, population: Population) -> None:
        """Store a population about to be shown; remember it for this step's answer."""
        pop = PopulationRow(
            trial_id=trial.id,
            attempt=population.trial,
            generation=population.generation,
            shown_at=utcnow(),
        )
        db.add(pop)
        db.flush()
        weights = full_weights(population).tolist()
        db.execute(
            insert(FaceRow),
            [
                {
                    "population_id": pop.id,
                    "position": i,
                    "face_id": int(population.ids[i]),
                    "parent_a": int(population.parent_ids[i, 0]),
                    "parent_b": int(population.parent_ids[i, 1]),
                    "operator": str(population.operators[i]),
                    "genes": dumps(population.genes[i].tolist()),
                    "weights": dumps(weights[i]),
                }
                for i in range(len(population))
            ],
        )
        db.info["shown"] = (
            trial.id,
            population.trial,
            population.generation,
            [{"id": int(i), "weights": w} for i, w in zip(population.ids, weights, strict=True)],
        )

    def _state(self, db: Session, sess: SessionRow) -> dict[str, Any]:
        cfg = self.ctx.config
        n_trials = len(json.loads(sess.trial_order))
        out: dict[str, Any] = {
            "stage": sess.stage,
            "participant_id": sess.participant_id,
            "progress": {
                "trial": sess.current_trial,
                "trials": n_trials,
                "generation": 0,
                "generations": cfg.ga.generations,
            },
            "limits": {
                "min_selections": cfg.ga.min_selections,
                "max_selections": cfg.ga.max_selections,
            },
            "allow_restart": cfg.allow_restart,
            "trial": None,
            "population": None,
            "rating": None,
            "completion": None,
        }
        if sess.stage == "done":
            out["completion"] = self.completion(sess.participant_id)
            out["progress"]["trial"] = n_trials - 1
            out["progress"]["generation"] = cfg.ga.generations
            return out
        if sess.stage != "trial":
            return out
        row = db.scalar(
            select(TrialRow).where(
                TrialRow.session_id == sess.id, TrialRow.position == sess.current_trial
            )
        )
        if row is None:  # pragma: no cover
            return out
        out["trial"] = {
            "position": row.position,
            "emotion": row.emotion,
            "prompt": cfg.prompt_for(row.emotion),
            "identity": row.identity,
            "attempt": row.attempt,
            "status": row.status,
        }
        out["progress"]["generation"] = row.generation
        if row.status == "active":
            shown = db.info.get("shown")
            pop = None
            if shown is None or shown[:3] != (row.id, row.attempt, row.generation):
                pop = db.scalar(
                    select(PopulationRow)
                    .where(
                        PopulationRow.trial_id == row.id,
                        PopulationRow.attempt == row.attempt,
                        PopulationRow.generation == row.generation,
                    )
                    .options(selectinload(PopulationRow.faces))
                )
            if shown is not None and shown[:3] == (row.id, row.attempt, row.generation):
                out["population"] = {
                    "attempt": row.attempt,
                    "generation": row.generation,
                    "faces": shown[3],
                }
            elif pop is not None:
                out["population"] = {
                    "attempt": pop.attempt,
                    "generation": pop.generation,
                    "faces": [
                        {"id": f.face_id, "weights": json.loads(f.weights)} for f in pop.faces
                    ],
                }
        elif row.status == "rating":
            face = db.scalar(
                select(FaceRow)
                .join(PopulationRow, FaceRow.population_id == PopulationRow.id)
                .where(
                    PopulationRow.trial_id == row.id,
                    PopulationRow.attempt == row.attempt,
                    FaceRow.face_id == row.final_face_id,
                )
            )
            out["rating"] = {
                "question": cfg.rating.question,
                "low_label": cfg.rating.low_label,
                "high_label": cfg.rating.high_label,
                "points": cfg.rating.points,
                "face": None
                if face is None
                else {"id": face.face_id, "weights": json.loads(face.weights)},
            }
        return out

    def completion(self, participant_id: str) -> dict[str, Any]:
        c = self.ctx.config.completion
        url = None
        if c.redirect_url:
            from urllib.parse import quote

            url = c.redirect_url.replace("{code}", quote(c.code or "", safe="")).replace(
                "{participant}", quote(participant_id, safe="")
            )
        return {"message": c.message, "code": c.code, "redirect_url": url}

    # ---- faces for the fallback renderer -------------------------------------------------
    def face_weights(self, token: str, face_id: int) -> tuple[np.ndarray, str]:
        """(full weights (n_columns,), identity) of a face of the caller's current trial."""
        with self.store.read() as db:
            sess = self._session(db, token)
            if sess.stage != "trial":
                raise SessionNotFound("no faces are shown now")
            found = db.execute(
                select(FaceRow.weights, TrialRow.identity)
                .join(PopulationRow, FaceRow.population_id == PopulationRow.id)
                .join(TrialRow, PopulationRow.trial_id == TrialRow.id)
                .where(
                    TrialRow.session_id == sess.id,
                    TrialRow.position == sess.current_trial,
                    FaceRow.face_id == face_id,
                )
                .limit(1)
            ).first()
            if found is None:
                raise SessionNotFound(f"face {face_id} is not in this session's current trial")
            return np.asarray(json.loads(found[0]), dtype=np.float64), str(found[1])
