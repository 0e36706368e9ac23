"""Sessions' progress numbered as the participant saw it, and their personal links.

The participant's page reads "Trial t of T · Generation g of G + 1" (both from 1; a study with
``ga.generations = G`` shows generations 0 … G) and "Rating" once the trial's last generation is
chosen. The stored rows and the export tables count from 0 (``generation`` 0 … G); the researcher
dashboard and ``emogen study status --sessions`` show the participant's numbers
(:func:`progress_as_shown`), next to the stored ones.
"""

from __future__ import annotations

import json
from typing import Any

from sqlalchemy import and_, select

from emogen.errors import ConfigError
from emogen.study.errors import SessionNotFound
from emogen.study.export import session_progress
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, StudyRow, TrialRow
from emogen.tasks.registry import task_named


def _generations(config_json: str) -> int:
    return int(json.loads(config_json).get("ga", {}).get("generations", 0))


def shown_step(
    line: dict[str, Any], generations: int, trial_status: str | None, task: str | None = None
) -> dict[str, Any]:
    """The participant's numbers of one :func:`session_progress` line (a new dict); ``task``:
    the current trial's, which says where in the trial the participant is
    (:meth:`emogen.tasks.protocol.Task.progress_step`)."""
    trials = int(line["trials"])
    trial = min(int(line["trial"]), trials)  # a finished session has moved past its last trial
    out = {**line, "trial": trial, "generations_shown": generations + 1, "generation_shown": None}
    if line["stage"] in ("instructions", "done") or task is None:
        out["step"] = str(line["stage"])
        return out
    where, shown = task_named(task).progress_step(
        trial_status or "", int(line["generation"] or 0), generations
    )
    out["generation_shown"] = shown
    out["step"] = f"trial {trial} of {trials} · {where}"
    return out


def progress_as_shown(store: Store, study_id: int | None = None) -> list[dict[str, Any]]:
    """:func:`session_progress` with ``step`` ("trial 2 of 6 · generation 3 of 11", "… · rating",
    "… · <task>", "instructions", "done"), ``generation_shown`` (from 1; none outside a
    generation) and ``generations_shown`` (G + 1) as the participant's page shows them."""
    lines = session_progress(store, study_id)
    with store.read() as db:
        generations = {
            sid: _generations(cfg)
            for sid, cfg in db.execute(select(StudyRow.id, StudyRow.config_json))
        }
        query = select(SessionRow.id, TrialRow.status, TrialRow.task).join(
            TrialRow,
            and_(
                TrialRow.session_id == SessionRow.id, TrialRow.position == SessionRow.current_trial
            ),
        )
        if study_id is not None:
            query = query.where(SessionRow.study_id == study_id)
        current = {sid: (str(st), str(task)) for sid, st, task in db.execute(query)}
    return [
        shown_step(
            line,
            generations.get(line["study_id"], 0),
            *current.get(line["session_id"], (None, None)),
        )
        for line in lines
    ]


def participant_token(
    store: Store, participant_id: str, *, study_id: int | None = None, study: str | None = None
) -> str:
    """The token of the participant's session (in the study of this id or name).

    A participant with sessions in several studies needs ``study``; in several versions of one
    study's config, the newest session is the one the participant was last given.
    """
    with store.read() as db:
        query = (
            select(SessionRow.token, StudyRow.name)
            .join(StudyRow, StudyRow.id == SessionRow.study_id)
            .where(SessionRow.participant_id == participant_id)
            .order_by(SessionRow.id.desc())
        )
        if study_id is not None:
            query = query.where(SessionRow.study_id == study_id)
        if study is not None:
            query = query.where(StudyRow.name == study)
        found = [(str(token), str(name)) for token, name in db.execute(query)]
    where = f" in study '{study}'" if study is not None else ""
    if not found:
        raise SessionNotFound(
            f"participant '{participant_id}' has no session{where} in this database; check the "
            "id (it is the one in the study link, e.g. ?PROLIFIC_PID=…)"
        )
    names = sorted({name for _, name in found})
    if len(names) > 1:
        raise ConfigError(
            f"participant '{participant_id}' has sessions in several studies ({', '.join(names)}); "
            "choose one with --study"
        )
    return found[0][0]


def session_link(base_url: str, token: str) -> str:
    """The participant's personal link: ``<base_url>/s/<token>``."""
    base = base_url.strip().rstrip("/")
    if not base.startswith(("http://", "https://")):
        raise ConfigError(
            f"the base URL must start with http:// or https://; got {base_url[:60]!r}"
        )
    return f"{base}/s/{token}"
