"""Consent given: a participant's session is made (or resumed with its token).

A session gets the next number in the study (arrival order, counted under the study's lock), a
seed that depends on the participant id alone (a keyed hash with the study seed:
:mod:`emogen.study.design`), a trial order whose Latin-square row is that hash's or, with
``counterbalance = "arrival"``, the session's number modulo the rows (exactly balanced in
arrival order), and one trial row per condition, each with its own seed.
"""

from __future__ import annotations

import hashlib
import re
import secrets

import numpy as np
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from emogen import __version__
from emogen.errors import ConfigError
from emogen.rng import spawn_seeds
from emogen.study.context import StudyContext
from emogen.study.design import assignment_slot, participant_seed, trial_order
from emogen.study.errors import StepConflict, StudyError
from emogen.study.queries import (
    count_sessions,
    lock_study,
    session_of_create_key,
    session_of_participant,
)
from emogen.study.retest import check_retest
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, TrialRow, dumps, utcnow
from emogen.study.view import SessionState, session_state
from emogen.tasks.protocol import TaskEnv

#: Matched whole (``fullmatch``): ``$`` would also match before a trailing newline.
PARTICIPANT_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9._:@+-]{0,127}")


class ParticipantRequired(StudyError):
    """A session asked for without a participant id, in a study that requires one."""


#: A creation key already bound to another participant's session (409).
KEY_TAKEN = (
    "this creation key already started another participant's session: reload the study's "
    "link (the page makes a key of its own for each participant id)"
)


def missing_advice(param: str) -> tuple[str, str]:
    """What a participant reads when the link lacks the id (the page and the API say it)."""
    return (
        f"This study needs your participant id in the link (…?{param}=YOUR_ID).",
        "Open the study again from the page that gave you the link (a copied link is sometimes "
        "cut short), or contact the researcher.",
    )


def checked_participant(
    participant_id: str | None, *, required_param: str | None = None
) -> tuple[str, str]:
    """(participant id, its source): the URL's id checked, or a generated one when none came
    (``required_param``: the study requires an id, named by this URL parameter)."""
    if participant_id is None or participant_id == "":
        if required_param is not None:
            raise ParticipantRequired(
                "the link has no participant id. " + " ".join(missing_advice(required_param))
            )
        return "anon-" + secrets.token_hex(8), "generated"
    if not PARTICIPANT_ID.fullmatch(participant_id):
        raise ConfigError(
            f"participant id must be 1-128 letters, digits or ._:@+- (starting with a letter "
            f"or digit); got {participant_id[:40]!r}"
        )
    return participant_id, "url"


def key_hash(create_key: str | None) -> str | None:
    """What is stored of a creation key (it is as secret as the session's token)."""
    return None if create_key is None else hashlib.sha256(create_key.encode()).hexdigest()


def _new_session(
    db: Session,
    ctx: StudyContext,
    participant_id: str,
    source: str,
    user_agent: str,
    create_key: str | None,
) -> SessionRow:
    cfg = ctx.config
    number = count_sessions(db, ctx.accepted)
    seed = participant_seed(cfg.seed, participant_id)
    conditions = ctx.conditions
    order_seed, *trial_seeds = spawn_seeds(seed, len(conditions) + 1)
    slot = assignment_slot(cfg, participant_id, arrival=number)
    order = trial_order(cfg, conditions, slot=slot, rng=np.random.default_rng(order_seed))
    now = utcnow()
    sess = SessionRow(
        study_id=ctx.study_id,
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
        user_agent=user_agent[:256] if cfg.collect_user_agent else None,
        create_key=create_key,
        created_at=now,
        consented_at=now,
        updated_at=now,
    )
    db.add(sess)
    db.flush()
    for pos, cond in enumerate(order.order):
        c = conditions[cond]
        db.add(
            TrialRow(
                session_id=sess.id,
                position=pos,
                block=c.block,
                task=c.task,
                condition=cond,
                emotion=c.emotion,
                identity=c.identity,
                repetition=c.repetition,
                seed=trial_seeds[pos],
                status="pending",
                attempt=0,
                generation=0,
            )
        )
    db.flush()
    return sess


def _theirs(sess: SessionRow, resume_token: str | None, create_key: str | None) -> bool:
    """Whether the request holds the session: its token, or the key it was created with."""
    if resume_token is not None and secrets.compare_digest(sess.token, resume_token):
        return True
    return (
        create_key is not None
        and sess.create_key is not None
        and (secrets.compare_digest(sess.create_key, create_key))
    )


def _existing(
    db: Session,
    ctx: StudyContext,
    pid: str,
    source: str,
    resume_token: str | None,
    create_key: str | None,
) -> SessionRow | None:
    """The session this request is a retry or a resumption of (None: make one); a conflict
    when the participant has a session the request does not hold."""
    if source == "generated" and create_key is not None:  # an anonymous create, retried
        found = session_of_create_key(db, ctx.accepted, create_key)
        if found is not None and found.participant_source != "generated":
            raise StepConflict(KEY_TAKEN)  # a named participant's key: never theirs to open
        return found
    existing = session_of_participant(db, ctx.all_versions or ctx.accepted, pid)
    if existing is None:
        return None
    if existing.study_id not in ctx.accepted:
        raise StepConflict(
            f"participant '{pid}' has already taken part in an earlier version of this study; "
            "please contact the researcher"
        )
    if ctx.config.resume == "participant_id" and source == "url":
        return existing  # the study trusts the id (docs/jspsych.md: resuming by id)
    if not _theirs(existing, resume_token, create_key):
        raise StepConflict(
            f"participant '{pid}' already has a session in this study: open your "
            "personal session link (shown on the first page of your session), or ask "
            "the researcher for it"
        )
    return existing


def create_session(
    store: Store,
    env: TaskEnv,
    participant_id: str | None,
    *,
    resume_token: str | None = None,
    create_key: str | None = None,
    user_agent: str = "",
    source: str | None = None,
) -> tuple[str, SessionState]:
    """A new session (token, state), or the participant's own one again.

    A participant id that already has a session is resumed only by the browser that holds it:
    with that session's token (``resume_token``) or with the creation key the consent page made
    before its first try (``create_key``: a retried create whose answer was lost — a crash after
    the commit, a proxy timeout, a mobile drop — gets the same session, as does an anonymous
    participant's retry); otherwise it is a conflict. ``user_agent`` is stored only when the
    study collects it (``collect_user_agent``). ``source`` records where the id came from
    instead of the URL (``simulated``).
    """
    ctx: StudyContext = env.ctx
    cfg = ctx.config
    required = cfg.participant_param if cfg.participant_required and source is None else None
    pid, given = checked_participant(participant_id, required_param=required)
    source = source or given
    hashed = key_hash(create_key)

    def work(db: Session) -> tuple[str, SessionState]:
        lock_study(db, ctx.study_id)  # one new session at a time per study (session numbers)
        existing = _existing(db, ctx, pid, given, resume_token, hashed)
        if existing is None:
            if hashed is not None and session_of_create_key(db, ctx.accepted, hashed):
                raise StepConflict(KEY_TAKEN)  # a key is bound to the participant it made
            check_retest(db, cfg.retest_of, pid)  # a retest: only the first session's people
            existing = _new_session(db, ctx, pid, source, user_agent, hashed)
        return existing.token, session_state(db, env, existing)

    for _ in range(3):
        try:
            return store.transact(work)
        except IntegrityError:  # the same participant or session number at the same moment
            continue
    raise StepConflict("the server is busy creating sessions; please try again")
