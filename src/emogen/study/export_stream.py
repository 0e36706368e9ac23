"""Exports of any size in bounded memory, and incremental exports of a study in progress.

The tables (see :mod:`emogen.study.export`) are made a few sessions at a time: a chunk of
sessions is read (:func:`~emogen.study.export_rows.load_records`), each table's rows of that
chunk are built by the same row functions as :func:`~emogen.study.export.export_tables`, made a
DataFrame typed by the export's one set of column rules (:mod:`emogen.columns`, through
:func:`emogen.study.export._frame`) and spilled to a temporary Arrow file. Then each table is written from its chunks in order, every
chunk cast to the table's one schema (the union of the chunks' columns and types, as one
DataFrame of all the rows would have had), as Parquet (row groups of a few chunks, with the
same provenance metadata as :func:`~emogen.study.export.write_export`) or CSV (formulas
neutralised, seeds and times in the CSV form of :mod:`emogen.columns`). Memory holds a chunk or a row group, whatever the study's size.

Incremental exports (``since``): a session is exported once it is *completed*, whole — its
session row, trials, faces, selections, restarts and ratings; nothing of it changes after
completion, so appending the tables of successive incremental exports never duplicates or drops
a row. An export with ``since = S`` holds the sessions completed at or after S and before its
cut-off U (``until``), which is the export's start time less :data:`SETTLE` (a step's
transaction takes its timestamp before it commits, so sessions completed just before the start
may not be visible yet; after SETTLE they are). The export records U in ``export.json``; the
next incremental export takes ``since = U``. The ``identities`` and ``study`` tables are
written whole every time (replace them, do not append them). Sessions never completed appear
only in full exports (no ``since``).
"""

from __future__ import annotations

import json
import shutil
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
from sqlalchemy import select

from emogen import columns as tidy
from emogen.errors import ConfigError
from emogen.study.export import (
    _frame,
    all_tables,
    export_provenance,
    former_names,
    identity_rows,
    neutralise_formulas,
    session_tables,
    study_rows,
    table_extras,
)
from emogen.study.export_rows import iso, load_records
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, StudyRow, as_utc
from emogen.tasks.registry import TASKS

#: How long before an incremental export's start its cut-off lies (see the module docstring).
SETTLE = timedelta(seconds=60)
#: Rows of the tasks' export tables per chunk (each task says how many a session has: the GA's
#: faces are the largest table).
CHUNK_ROWS = 500
#: A Parquet row group: several chunks, up to this many rows or this many bytes in memory
#: (the faces table is wide: ~100 columns).
ROW_GROUP_ROWS = 8192
ROW_GROUP_BYTES = 4 << 20


def parse_since(text: str) -> datetime:
    """An ISO 8601 time (``2026-05-01T12:00:00+00:00``, ``2026-05-01 12:00``; no zone: UTC)."""
    try:
        t = datetime.fromisoformat(text.strip())
    except ValueError:
        raise ConfigError(
            f"--since must be an ISO 8601 time such as 2026-05-01T12:00:00+00:00 (the 'until' "
            f"of the previous export); got {text!r}"
        ) from None
    try:
        return t.replace(tzinfo=UTC) if t.tzinfo is None else t.astimezone(UTC)
    except OverflowError:  # 9999-12-31T23:59-23:59 is past the last time UTC can hold
        raise ConfigError(
            f"--since must be a time between 0001-01-01 and 9999-12-31 in UTC; got {text!r}"
        ) from None


def check_table_names(tables: tuple[str, ...] | list[str]) -> None:
    """Every name one of :func:`all_tables` (an old name is named with its new one)."""
    known, formerly = all_tables(), former_names()
    for name in tables:
        if name in formerly:
            raise ConfigError(
                f"--table {name!r} is called {formerly[name]!r} since schema emogen.study/6"
            )
        if name not in known:
            raise ConfigError(f"--table must be one of {', '.join(known)}; got {name!r}")


@dataclass(frozen=True)
class ExportResult:
    """What an export wrote: paths, rows per table, and its window (``until``: the next
    incremental export's ``since``; None for a full export)."""

    paths: list[Path]
    rows: dict[str, int]
    since: datetime | None
    until: datetime | None


def _studies(store: Store, study: str | None) -> dict[int, StudyRow]:
    with store.read() as db:
        studies = {s.id: s for s in db.scalars(select(StudyRow))}
    if study is not None:
        studies = {k: v for k, v in studies.items() if v.name == study}
        if not studies:
            raise ConfigError(f"no study named '{study}' in {store.describe()}")
    return studies


def session_chunks(
    store: Store, study_ids: list[int], since: datetime | None, until: datetime | None
) -> list[list[int]]:
    """The sessions to export, in id order, in chunks of about :data:`CHUNK_ROWS` rows of the
    tasks' export tables."""
    query = select(SessionRow.id).where(SessionRow.study_id.in_(study_ids)).order_by(SessionRow.id)
    if until is not None:
        query = query.where(SessionRow.completed_at.is_not(None), SessionRow.completed_at < until)
    if since is not None:
        query = query.where(SessionRow.completed_at >= since)
    chunks: list[list[int]] = []
    size = 0
    with store.read() as db:
        rows: dict[int, int] = {}
        for task in TASKS.values():
            for sid, n in task.export_size(db, query.order_by(None)).items():
                rows[sid] = rows.get(sid, 0) + n
        for sid in db.scalars(query):
            if not chunks or size + rows.get(sid, 0) > CHUNK_ROWS:
                chunks.append([])
                size = 0
            chunks[-1].append(int(sid))
            size += rows.get(sid, 0)
    return chunks


class _Spill:
    """Each table's chunks as Arrow files in a temporary folder, in order."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        names = all_tables()
        self.files: dict[str, list[Path]] = {name: [] for name in names}
        self.rows: dict[str, int] = dict.fromkeys(names, 0)
        self.empty: dict[str, pa.Table] = {}

    def add(self, name: str, frame: pd.DataFrame) -> None:
        table = pa.Table.from_pandas(frame, schema=tidy.arrow_schema(frame), preserve_index=False)
        if table.num_rows == 0:  # kept only for its columns, in case no rows come
            self.empty.setdefault(name, table)
            return
        path = self.folder / f"{name}-{len(self.files[name]):06d}.arrow"
        with pa.OSFile(str(path), "wb") as sink, pa.ipc.new_file(sink, table.schema) as writer:
            writer.write_table(table)
        self.files[name].append(path)
        self.rows[name] += table.num_rows

    def _read(self, path: Path) -> pa.Table:
        with pa.memory_map(str(path)) as source:
            return pa.ipc.open_file(source).read_all()

    def chunks(self, name: str) -> tuple[pa.Schema, Iterator[pa.Table]]:
        """The table's schema (every chunk's columns and types, unified) and its chunks."""
        files = self.files[name]
        if not files:
            table = self.empty[name]
            return table.schema, iter([table])
        schemas = []
        for path in files:
            with pa.memory_map(str(path)) as source:
                schemas.append(pa.ipc.open_file(source).schema)
        schema = pa.unify_schemas(
            schemas, promote_options="permissive"
        )  # first chunk's pandas metadata

        def tables() -> Iterator[pa.Table]:
            for path in files:
                table = self._read(path)
                for field in schema:
                    if field.name not in table.column_names:
                        table = table.append_column(field, pa.nulls(table.num_rows, field.type))
                yield table.select(schema.names).cast(schema)

        return schema, tables()


def _row_groups(tables: Iterator[pa.Table]) -> Iterator[pa.Table]:
    """The chunks gathered into row groups of about :data:`ROW_GROUP_ROWS` rows or
    :data:`ROW_GROUP_BYTES` (a Parquet file's footer holds every row group's column metadata:
    many small groups would make it, and the writer's memory, grow with the study; large ones
    hold more rows in memory at once)."""
    buffer: list[pa.Table] = []
    rows = size = 0
    for table in tables:
        buffer.append(table)
        rows += table.num_rows
        size += table.nbytes
        if rows >= ROW_GROUP_ROWS or size >= ROW_GROUP_BYTES:
            yield pa.concat_tables(buffer)
            buffer, rows, size = [], 0, 0
    if buffer:
        yield pa.concat_tables(buffer)


def _write(spill: _Spill, name: str, path: Path, fmt: str, provenance: dict[str, Any]) -> None:
    schema, tables = spill.chunks(name)
    if fmt == "parquet":
        meta = {
            **(schema.metadata or {}),
            **tidy.provenance_metadata({**provenance, "table": name}),
        }
        schema = schema.with_metadata(meta)
        with pq.ParquetWriter(str(path), schema) as writer:
            for group in _row_groups(tables):
                writer.write_table(group)
        return
    empty = schema.empty_table().to_pandas(types_mapper=tidy.pandas_types)
    tidy.write_col_types(path.parent, {name: tidy.readr_types(empty)})
    with open(path, "w", encoding="utf-8", newline="") as out:
        for i, table in enumerate(tables):
            frame = neutralise_formulas(table.to_pandas(types_mapper=tidy.pandas_types))
            out.write(str(tidy.csv_frame(frame).to_csv(index=False, header=i == 0)))


def export_study(
    store: Store,
    out: Path,
    fmt: str = "parquet",
    *,
    study: str | None = None,
    since: datetime | None = None,
    tables: tuple[str, ...] | None = None,
    now: datetime | None = None,
) -> ExportResult:
    """Write ``<table>.<fmt>`` for ``tables`` into ``out`` in bounded memory (module doc);
    with ``since``, only the sessions completed in [since, now − SETTLE), and ``export.json``."""
    if fmt not in ("parquet", "csv"):
        raise ConfigError(f"--format must be parquet or csv; got {fmt!r}")
    tables = all_tables() if tables is None else tables
    check_table_names(tables)
    studies = _studies(store, study)
    until = None
    if since is not None:
        until = (as_utc(now) or datetime.now(UTC)) - SETTLE
        since = as_utc(since)
    chunks = session_chunks(store, sorted(studies), since, until)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    folder = Path(tempfile.mkdtemp(prefix="emogen-export-", dir=out))
    try:
        spill = _Spill(folder)
        ordered = [studies[sid] for sid in sorted(studies)]
        extras = table_extras(ordered)
        _spill_sessions(store, studies, chunks, spill, tables, extras)
        if "identities" in tables:
            rows = [r for sid in sorted(studies) for r in identity_rows(studies[sid])]
            spill.add("identities", _frame("identities", rows, []))
        study_table = _frame("study", list(study_rows(ordered)), [])
        if "study" in tables:
            spill.add("study", study_table)
        provenance = export_provenance({"study": study_table})
        paths = []
        for name in tables:
            path = out / f"{name}.{fmt}"
            _write(spill, name, path, fmt, provenance)
            paths.append(path)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if since is not None:
        manifest = {"since": iso(since), "until": iso(until), "sessions": sum(map(len, chunks))}
        (out / "export.json").write_text(json.dumps(manifest, indent=2) + "\n")
    return ExportResult(paths, {t: spill.rows[t] for t in tables}, since, until)


def _spill_sessions(
    store: Store,
    studies: dict[int, StudyRow],
    chunks: list[list[int]],
    spill: _Spill,
    tables: tuple[str, ...],
    extras: dict[str, list[str]],
) -> None:
    """Every chunk's rows of the per-session tables, read and spilled one chunk at a time."""
    known = session_tables()
    per_session = [name for name in tables if name in known]
    for name in per_session:
        spill.add(name, _frame(name, [], extras.get(name, [])))
    for ids in chunks:
        with store.read() as db:
            rec = load_records(db, studies, ids)
        for name in per_session:
            rows = list(known[name].rows(rec))
            spill.add(name, _frame(name, rows, extras.get(name, [])))
        del rec
