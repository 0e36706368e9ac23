"""Researcher side: study progress, and tidy export tables in Parquet or CSV.

Tables (one row per …): ``sessions`` (session), ``trials`` (trial of a session), then each
registered task's own tables (:attr:`emogen.tasks.protocol.Task.export_tables`, in the task's
``export`` module; docs/data.md lists them all),
``identities`` (identity of a study: its ``shape`` —
a preset name, or ``shape_coefficients`` as a JSON list — and one column per appearance
parameter, with ``appearance_generator``, so any stimulus can be re-rendered exactly; join on
``study`` and ``identity``), and ``study`` (study: its resolved config itself as
``config_json``, the model, gene and weight column names, ``framing``: what participants saw
around each face). Every row carries ``schema_version``, ``package_version`` (the version that
recorded the session; for ``identities``, the study), ``model_hash`` and ``study_config_hash``.
A session's trial order is the ``trials`` table (``trial``: position, ``condition``).

Column types, the CSV form (seeds as ``s<digits>``, ISO 8601 times) and the provenance in every
Parquet file's metadata follow :mod:`emogen.columns`; every column is in docs/data.md.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pandas as pd
from sqlalchemy import func, select

from emogen import columns as tidy
from emogen.appearance.identities import Identity
from emogen.appearance.params import GENERATOR_VERSION, Appearance
from emogen.errors import ConfigError
from emogen.study.config import StudyConfig
from emogen.study.dashboard import seconds_between
from emogen.study.export_rows import SESSIONS, TRIALS, iso, load_records
from emogen.study.storage import Store
from emogen.study.tables import SCHEMA_VERSION, SessionRow, StepRow, StudyRow, TrialRow
from emogen.tasks.export import ExportTable, Row
from emogen.tasks.registry import TASKS


def session_tables() -> dict[str, ExportTable]:
    """The per-session tables: the study's own, then each registered task's
    (:attr:`emogen.tasks.protocol.Task.export_tables`, made from a read's records)."""
    tasks = [table for task in TASKS.values() for table in task.export_tables]
    return {t.name: t for t in (SESSIONS, TRIALS, *tasks)}


def all_tables() -> tuple[str, ...]:
    """Every table of an export, in order; the study-wide ones last."""
    return (*session_tables(), "identities", "study")


def former_names() -> dict[str, str]:
    """The tables' names before schema 6 (``emogen.study/5`` and older exports): old → new."""
    return {t.formerly: t.name for t in session_tables().values() if t.formerly}


#: The tables of the tasks registered when this module was imported (the built-in ones).
SESSION_TABLES = session_tables()
TABLES = all_tables()
FORMERLY = former_names()
#: The fixed columns of the study-wide tables (``identities`` adds the appearance parameters).
STUDY_TABLE_COLUMNS = {
    "identities": ["study", "identity", "shape", "shape_coefficients"],
    "study": [
        *("study", "config_json", "model_name", "gene_names", "weight_names", "framing"),
        "created_at",
    ],
}
STAMPS = ("schema_version", "package_version", "model_hash", "study_config_hash")


def study_status(store: Store) -> list[dict[str, Any]]:
    """Per study: sessions by stage, trials done, and the steps taken by command (``select``,
    ``answer``, …: one a page's request the server acted on, a repeat not counted)."""
    out = []
    with store.read() as db:
        for study in db.scalars(select(StudyRow).order_by(StudyRow.id)):
            stages = dict(
                db.execute(
                    select(SessionRow.stage, func.count())
                    .where(SessionRow.study_id == study.id)
                    .group_by(SessionRow.stage)
                ).all()
            )
            trials_done = db.scalar(
                select(func.count())
                .select_from(TrialRow)
                .join(SessionRow, TrialRow.session_id == SessionRow.id)
                .where(SessionRow.study_id == study.id, TrialRow.status == "done")
            )
            steps = dict(
                db.execute(
                    select(StepRow.kind, func.count())
                    .join(SessionRow, StepRow.session_id == SessionRow.id)
                    .where(SessionRow.study_id == study.id)
                    .group_by(StepRow.kind)
                ).all()
            )
            out.append(
                {
                    "study_id": study.id,
                    "name": study.name,
                    "config_hash": study.config_hash,
                    "model_hash": study.model_hash,
                    "created_at": iso(study.created_at),
                    "sessions": int(sum(stages.values())),
                    "by_stage": {k: int(v) for k, v in sorted(stages.items())},
                    "trials_done": int(trials_done or 0),
                    "steps": {str(k): int(v) for k, v in sorted(steps.items())},
                }
            )
    return out


def session_progress(store: Store, study_id: int | None = None) -> list[dict[str, Any]]:
    """One line per session: participant, stage, trial and generation reached (no tokens)."""
    out = []
    with store.read() as db:
        query = select(SessionRow).order_by(SessionRow.id)
        if study_id is not None:
            query = query.where(SessionRow.study_id == study_id)
        sessions = list(db.scalars(query))
        cur = {
            (t.session_id, t.position): t
            for t in db.scalars(
                select(TrialRow).where(TrialRow.session_id.in_([s.id for s in sessions]))
            )
        }
        for s in sessions:
            t = cur.get((s.id, s.current_trial))
            out.append(
                {
                    "session_id": s.id,
                    "session_number": s.number,
                    "study_id": s.study_id,
                    "participant_id": s.participant_id,
                    "order_row": None if s.order_row < 0 else s.order_row,
                    "stage": s.stage,
                    "trial": s.current_trial + 1,
                    "trials": len(json.loads(s.trial_order)),
                    "generation": None if t is None else t.generation,
                    "attempt": None if t is None else t.attempt + 1,
                    "created_at": iso(s.created_at),
                    "updated_at": iso(s.updated_at),
                    "completed_at": iso(s.completed_at),
                    "duration_s": seconds_between(s.consented_at, s.completed_at or s.updated_at),
                }
            )
    return out


def export_tables(
    store: Store, *, study: str | None = None, session_ids: list[int] | None = None
) -> dict[str, pd.DataFrame]:
    """Every table (see the module doc) as a DataFrame; ``study`` limits to studies of that name."""
    with store.read() as db:
        studies = {s.id: s for s in db.scalars(select(StudyRow))}
        if study is not None:
            studies = {k: v for k, v in studies.items() if v.name == study}
            if not studies:
                raise ConfigError(f"no study named '{study}' in {store.describe()}")
        rec = load_records(db, studies, session_ids)
    rows: dict[str, list[dict[str, Any]]] = {
        name: list(table.rows(rec)) for name, table in session_tables().items()
    }
    rows["identities"] = []
    shown = {s.study_id for s in rec.sessions} if session_ids is not None else set(studies)
    for sid in sorted(shown):
        rows["identities"].extend(identity_rows(studies[sid]))
    rows["study"] = list(study_rows([studies[sid] for sid in sorted(shown)]))
    extra = table_extras([studies[sid] for sid in sorted(shown)])
    return {name: _frame(name, rows[name], extra.get(name, [])) for name in all_tables()}


def table_extras(studies: list[StudyRow]) -> dict[str, list[str]]:
    """The columns a table has beyond its fixed ones, for these studies: the ``g_<gene>`` and
    ``w_<weight>`` columns of the tables of faces (present even when no face has been shown)."""
    names = [json.loads(s.gene_names) for s in studies]
    weights = [json.loads(s.weight_names) for s in studies]
    face_columns = [
        *dict.fromkeys(f"g_{n}" for ns in names for n in ns),
        *dict.fromkeys(f"w_{n}" for ns in weights for n in ns),
    ]
    return {name: face_columns for name, t in session_tables().items() if t.faces}


def identity_rows(study: StudyRow) -> list[dict[str, Any]]:
    """One row per identity of ``study`` (from its recorded config): shape and appearance."""
    config = StudyConfig.model_validate(json.loads(study.config_json))
    out = []
    for name, ident in config.study_identities().items():
        coeffs = None if isinstance(ident.shape, str) else json.dumps(list(ident.shape))
        out.append(
            {
                "study": study.name,
                "identity": name,
                "shape": ident.shape if isinstance(ident.shape, str) else None,
                "shape_coefficients": coeffs,
                **ident.appearance.record(),
                "appearance_generator": GENERATOR_VERSION,
                "schema_version": SCHEMA_VERSION,
                "package_version": study.package_version,
                "model_hash": study.model_hash,
                "study_config_hash": study.config_hash,
            }
        )
    return out


def identities_from_table(table: pd.DataFrame) -> dict[tuple[str, str], Identity]:
    """The ``identities`` export table (as read back from Parquet or CSV) as identities, by
    (study, identity name). An appearance parameter added after the export was written (e.g.
    ``lip_depth``) takes its default, which is the look the parameter's absence gave."""
    out = {}
    for row in table.to_dict("records"):
        coeffs = row.get("shape_coefficients")
        shape: str | tuple[float, ...] = (
            tuple(float(x) for x in json.loads(coeffs))
            if isinstance(coeffs, str) and coeffs
            else str(row["shape"])
        )
        values: dict[str, Any] = {
            k: tidy.seed_value(row[k]) if tidy.kind(k) == "seed" else row[k]
            for k in Appearance.model_fields
            if k in row
        }
        appearance = Appearance(**values)
        out[(str(row["study"]), str(row["identity"]))] = Identity(
            shape=shape, appearance=appearance
        )
    return out


def _frame(name: str, rows: list[dict[str, Any]], extra: list[str]) -> pd.DataFrame:
    """A table typed by :func:`emogen.columns.typed`; empty, it has all its columns."""
    tables = session_tables()
    if name in tables:
        table = tables[name]
        return tidy.frame(rows, [*table.column_names, *extra, *STAMPS], table.dtypes)
    columns = [*STUDY_TABLE_COLUMNS[name], *extra, *STAMPS]
    if name == "identities":
        columns[4:4] = [*Appearance().record(), "appearance_generator"]
    dtypes = {k: _APPEARANCE_DTYPES[type(v)] for k, v in Appearance().record().items()}
    return tidy.frame(rows, columns, dtypes if name == "identities" else None)


_APPEARANCE_DTYPES = {float: "float64", int: "Int64", str: "string", bool: "boolean"}


#: A text cell starting with one of these is a formula to a spreadsheet (CSV injection).
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def neutralise_formulas(df: pd.DataFrame) -> pd.DataFrame:
    """A copy whose text cells that a spreadsheet would run as formulas (starting with
    ``= + - @``, tab or CR) start with ``'`` instead; numbers (negative ones too) stay as they
    are. For CSV only: Parquet keeps the raw values."""

    def cell(v: Any) -> Any:
        return "'" + v if isinstance(v, str) and v.startswith(FORMULA_STARTS) else v

    out = df.copy()
    for col in out.columns:
        column = out[col]
        if column.dtype == object or pd.api.types.is_string_dtype(column.dtype):
            out[col] = column.map(cell)
    return out


def csv_text(df: pd.DataFrame) -> str:
    """One export table as CSV text, formulas neutralised (:func:`neutralise_formulas`)."""
    return tidy.csv_text(neutralise_formulas(df))


def export_provenance(tables: dict[str, pd.DataFrame]) -> dict[str, Any]:
    """What every exported Parquet file records of its making (its schema metadata): the
    schema, the exporting package version and, per study, its resolved config, seed, model and
    config hashes and the package version that recorded it."""
    from emogen import __version__

    studies = []
    study = tables.get("study")
    for row in [] if study is None else study.to_dict("records"):
        config = json.loads(str(row["config_json"]))
        studies.append(
            {
                "study": row["study"],
                "model_hash": row["model_hash"],
                "study_config_hash": row["study_config_hash"],
                "package_version": row["package_version"],
                "seed": config.get("seed"),
                "framing": config.get("framing", "face"),
                "config": config,
            }
        )
    return {"schema": SCHEMA_VERSION, "package_version": __version__, "studies": studies}


def write_export(tables: dict[str, pd.DataFrame], out: Path, fmt: str = "parquet") -> list[Path]:
    """``<table>.parquet`` or ``<table>.csv`` for every table, in ``out`` (CSV text cells
    that a spreadsheet would run as formulas are neutralised: :func:`neutralise_formulas`;
    beside CSV tables, their readr types: :func:`emogen.columns.write_col_types`)."""
    if fmt not in ("parquet", "csv"):
        raise ConfigError(f"--format must be parquet or csv; got {fmt!r}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    meta = export_provenance(tables)
    for name, df in tables.items():
        path = out / f"{name}.{fmt}"
        if fmt == "parquet":
            tidy.write_parquet(df, path, {**meta, "table": name})
        else:
            path.write_text(csv_text(df), encoding="utf-8")
        paths.append(path)
    if fmt == "csv":
        tidy.write_col_types(out, {name: tidy.readr_types(df) for name, df in tables.items()})
    return paths


def study_rows(studies: list[StudyRow]) -> Iterator[Row]:
    """One row per study: its resolved config itself (``config_json``, canonical JSON: the
    exact config its sessions ran with, and replay from exported files reads), not only its
    hash; the model, the gene and weight column names (JSON lists), the faces' framing."""
    for st in studies:
        yield {
            "study": st.name,
            "config_json": st.config_json,
            "model_name": st.model_name,
            "gene_names": st.gene_names,
            "weight_names": st.weight_names,
            # what participants saw around each face (appearance: no part of the GA's state)
            "framing": json.loads(st.config_json).get("framing", "face"),
            "created_at": iso(st.created_at),
            "schema_version": SCHEMA_VERSION,
            "package_version": st.package_version,
            "model_hash": st.model_hash,
            "study_config_hash": st.config_hash,
        }
