"""Replay sessions from exported files (``emogen study export``, Parquet or CSV) alone.

The export's ``study`` table carries each study's resolved config (``config_json``) and its
gene and weight column names; ``trials`` the trials' seeds. Each registered task replays its
own trials from the tables it names (:attr:`emogen.tasks.protocol.Task.replay_tables`, in
each task's own module), and each session's report gathers them.
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import pandas as pd

from emogen import columns as tidy
from emogen.errors import ConfigError
from emogen.model.load import model_for_recorded_hash
from emogen.model.rig import Rig
from emogen.study.config import StudyConfig
from emogen.study.context import accepted_hashes
from emogen.study.export import FORMULA_STARTS, former_names
from emogen.study.replay import ReplayReport
from emogen.study.weights import StudyCorrectors
from emogen.tasks.protocol import ExportedStudy, TaskEnv
from emogen.tasks.registry import TASKS

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

#: the tables every replay reads; each task adds its own
STUDY_TABLES = ("study", "sessions", "trials")


def needed() -> tuple[str, ...]:
    """The export tables a replay reads: the study's and every registered task's."""
    names = list(STUDY_TABLES)
    for task in TASKS.values():
        names += [n for n in task.replay_tables if n not in names]
    return tuple(names)


def _restore_text(v: Any) -> Any:
    """Undo the CSV export's formula neutralising (``'=…`` back to ``=…``)."""
    if isinstance(v, str) and v.startswith("'") and v[1:].startswith(FORMULA_STARTS):
        return v[1:]
    return v


def _read_table(folder: Path, name: str) -> pd.DataFrame | None:
    """``<name>.parquet``, else ``<name>.csv`` of an export folder; None when neither is."""
    pq, csv = folder / f"{name}.parquet", folder / f"{name}.csv"
    if pq.is_file():
        return pd.read_parquet(pq)
    if not csv.is_file():
        return None
    df = tidy.read_csv(csv)
    for col in df.columns:
        if df[col].dtype == object or pd.api.types.is_string_dtype(df[col].dtype):
            df[col] = df[col].map(_restore_text)
    return df


def read_exported(folder: Path) -> dict[str, pd.DataFrame]:
    """The tables replay needs from an export folder (``<table>.parquet``, else ``.csv``): the
    study's tables, or a clear error; each task's where the folder has it (under its name, or
    its name before schema 6) — a task whose table is missing says what it could not check."""
    folder = Path(folder)
    out = {}
    old = {new: old for old, new in former_names().items()}
    for name in needed():
        df = _read_table(folder, name)
        if df is None and name in old:
            df = _read_table(folder, old[name])
        if df is not None:
            out[name] = df
        elif name in STUDY_TABLES:
            raise ConfigError(
                f"export folder {folder} has no {name}.parquet or {name}.csv "
                "(write it with `emogen study export`; the study table needs emogen ≥ schema 2)"
            )
    return out


def _of_study(df: pd.DataFrame, study: str) -> pd.DataFrame:
    return df[df["study"].astype(str) == study]


def replay_exported(
    folder: Path,
    rig: Rig,
    model_hash: str,
    *,
    model: FaceModel | None = None,
    session_ids: list[int] | None = None,
) -> list[ReplayReport]:
    """One report per exported session (or per ``session_ids``), replayed from the files."""
    t = read_exported(folder)
    reports = []
    for study in t["study"].to_dict("records"):
        config = StudyConfig.model_validate(json.loads(study["config_json"]))
        mine = {name: _of_study(df, str(study["study"])) for name, df in t.items()}
        sessions = sorted(int(s) for s in mine["sessions"]["session_id"])
        if session_ids is not None:
            sessions = [s for s in sessions if s in session_ids]
        s_model, s_rig, s_hash = model, rig, model_hash
        if model is not None and model.model_hash == model_hash:  # an older packaged rig?
            s_model = model_for_recorded_hash(model, study["model_hash"])
            s_rig, s_hash = s_model.rig, s_model.model_hash
        exported = ExportedStudy(
            config=config,
            genes=json.loads(study["gene_names"]),
            weights=json.loads(study["weight_names"]),
            tables=mine,
            sessions=frozenset(sessions),
            rig=s_rig,
        )
        ctx = SimpleNamespace(config=config, rig=s_rig, conditions=(), accepted=())
        env = TaskEnv(ctx=ctx, correctors=StudyCorrectors(config, s_model))
        replayed = [task.replay_exported(env, exported) for task in TASKS.values()]
        matches = study["model_hash"] in accepted_hashes(s_hash, s_model)
        for sid in sessions:
            report = ReplayReport(sid, model_hash_matches=matches)
            for done in (d for by_session in replayed for d in by_session.get(sid, [])):
                report.take(done)
            reports.append(report)
    if session_ids is not None and not reports:
        raise ConfigError(f"no session {session_ids} in the export at {folder}")
    return reports
