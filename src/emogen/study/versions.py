"""Versions of a study config under one name: which running sessions a served config continues.

Every config served is a study row (its hash is stamped on every exported row). A config that
differs from an earlier one of the same name only in its texts (:data:`TEXT_KEYS`: consent,
instructions, prompt, rating and completion wording, where the database or model files are)
and that runs the same model has the same *design*: the sessions begun under the earlier
config go on under the new one (they show its texts) and keep their own row. A config whose
design differs would change what an unfinished session's remaining trials are, so
:func:`check_running_sessions` refuses it while sessions of another design are unfinished,
unless the researcher says how they continue: ``end`` stops them (their participants are told
the study changed; their data so far stay in the database and the exports, stage ``ended``).
A participant id takes part once per study name, whichever version it began under.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Literal

from sqlalchemy import func, select, update

from emogen.errors import ConfigError
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, StudyRow, utcnow

#: Keys (dotted for tables) whose change leaves the design alone: what participants read, and
#: where the files are (the model is compared by its hash).
TEXT_KEYS = (
    "title",
    "consent",
    "instructions",
    "prompt",
    "rating.question",
    "rating.low_label",
    "rating.high_label",
    "completion.message",
    "completion.code",
    "completion.redirect_url",
    "database_url",
    "model",
    "rig",
)
#: What ``serve --running-sessions`` may say about the unfinished sessions of another design.
RunningSessions = Literal["refuse", "end"]
UNFINISHED = ("instructions", "trial")
#: The stage of a session ended because the study's design changed under it.
ENDED = "ended"


def design(config_json: str) -> dict[str, Any]:
    """A stored config's JSON without its :data:`TEXT_KEYS`."""
    data = json.loads(config_json)
    for key in TEXT_KEYS:
        table, _, name = key.rpartition(".")
        holder = data.get(table, {}) if table else data
        if isinstance(holder, dict):
            holder.pop(name, None)
    return dict(data)


def changed_keys(old: dict[str, Any], new: dict[str, Any], prefix: str = "") -> list[str]:
    """The dotted keys whose values differ between two config dicts."""
    out: list[str] = []
    for key in sorted(set(old) | set(new)):
        a, b = old.get(key), new.get(key)
        if isinstance(a, dict) and isinstance(b, dict):
            out += changed_keys(a, b, f"{prefix}{key}.")
        elif a != b:
            out.append(prefix + key)
    return out


@dataclass(frozen=True)
class Versions:
    """The rows of one study name: those of this design (sessions continue), and all."""

    same_design: tuple[int, ...]
    all_versions: tuple[int, ...]


def study_versions(store: Store, study_id: int) -> Versions:
    with store.read() as db:
        me = db.get(StudyRow, study_id)
        if me is None:  # pragma: no cover - registered just before
            raise ConfigError(f"study row {study_id} is missing")
        rows = db.execute(
            select(StudyRow.id, StudyRow.config_json, StudyRow.model_hash).where(
                StudyRow.name == me.name
            )
        ).all()
        mine = design(me.config_json)
        same = tuple(
            sorted(
                r.id
                for r in rows
                if r.model_hash == me.model_hash and design(r.config_json) == mine
            )
        )
    return Versions(same, tuple(sorted(r.id for r in rows)))


def check_running_sessions(
    store: Store, study_id: int, versions: Versions, running: RunningSessions = "refuse"
) -> int:
    """Refuse (``ConfigError``) to serve ``study_id`` while sessions of another design of the
    same study are unfinished, unless ``running == "end"``: then they are ended (stage
    ``ended``). Returns how many were ended."""
    others = [i for i in versions.all_versions if i not in versions.same_design]
    if not others:
        return 0
    unfinished = SessionRow.study_id.in_(others), SessionRow.stage.in_(UNFINISHED)
    with store.read() as db:
        count = int(db.scalar(select(func.count()).select_from(SessionRow).where(*unfinished)) or 0)
        if count == 0:
            return 0
        newest = db.scalar(
            select(SessionRow.study_id).where(*unfinished).order_by(SessionRow.updated_at.desc())
        )
        me, old = db.get(StudyRow, study_id), db.get(StudyRow, newest)
        if me is None or old is None:  # pragma: no cover - both rows were just read
            raise ConfigError(f"study rows {study_id} and {newest} are missing")
        keys = changed_keys(design(old.config_json), design(me.config_json))
        name, model_changed = me.name, me.model_hash != old.model_hash
    if running != "end":
        what = ", ".join(keys[:8]) + (" …" if len(keys) > 8 else "")
        if model_changed:
            what = "the face model" + (f", {what}" if what else "")
        raise ConfigError(
            f"study '{name}' has {count} unfinished session{'s' if count != 1 else ''} begun "
            f"under a config whose design differs from this one (changed: {what or 'nothing'}); "
            "texts (consent, instructions, prompt, rating and completion wording) may change "
            "under running sessions, the design may not: serve the earlier config until they "
            "finish, or pass --running-sessions end to end them (their participants are told "
            "that the study changed)"
        )
    with store.write() as db:
        result = db.execute(
            update(SessionRow).where(*unfinished).values(stage=ENDED, updated_at=utcnow())
        )
    return int(getattr(result, "rowcount", 0) or 0)
