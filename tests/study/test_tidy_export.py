"""Study exports as R and pandas users read them: exact seeds, real timestamps, NA for missing,
one value per cell, the same schema when empty, provenance in every Parquet file, and every
column in docs/data.md. R reads the CSV files in tests/study/test_export_r.py."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
from sqlalchemy import select

from emogen import __version__
from emogen import columns as tidy
from emogen.study.export import SESSION_TABLES, TABLES, export_tables, write_export
from emogen.study.sessions import StudyService
from emogen.study.tables import SCHEMA_VERSION, SessionRow, TrialRow
from tests.r_readers import ISO_UTC, read_in_r, undocumented
from tests.study.test_export_replay import completed

#: Cells that hold a JSON document by design (docs/data.md says so): the resolved config, the
#: column-name lists replay needs, a custom identity's shape coefficients.
JSON_CELLS = {
    ("study", "config_json"),
    ("study", "gene_names"),
    ("study", "weight_names"),
    ("identities", "shape_coefficients"),
}


def _seeds(service: StudyService) -> dict[str, dict[int, int]]:
    with service.store.read() as db:
        sessions = {s.id: s.seed for s in db.scalars(select(SessionRow))}
        trials = {t.id: t.seed for t in db.scalars(select(TrialRow))}
        orders = {s.id: json.loads(s.trial_order) for s in db.scalars(select(SessionRow))}
    return {"sessions": sessions, "trials": trials, "orders": orders}


def test_parquet_export_is_typed_and_carries_its_provenance(
    service: StudyService, tmp_path: Path, ict_model
) -> None:  # type: ignore[no-untyped-def]
    completed(service, "T-1", restart=True)
    completed(service, "T-2")
    write_export(export_tables(service.store), tmp_path, "parquet")
    db = _seeds(service)
    big = [s for s in db["sessions"].values() if s > 2**53]
    assert big, "the test needs seeds above 2**53 (a double cannot hold them)"
    for name in TABLES:
        path = tmp_path / f"{name}.parquet"
        schema = pq.read_schema(path)
        for field in schema:
            if field.name.endswith("_at"):  # real timestamps, in UTC
                assert pa.types.is_timestamp(field.type) and field.type.tz == "UTC", field
            if field.name == "seed":
                assert field.type == pa.int64(), (name, field)
        meta = tidy.provenance(path)
        assert meta["schema"] == SCHEMA_VERSION and meta["table"] == name
        assert meta["package_version"] == __version__
        assert "git_commit" in meta
        (study,) = meta["studies"]
        assert study["model_hash"] == ict_model.model_hash
        assert study["seed"] == 1234 and study["config"]["name"] == "small"
    sessions = pd.read_parquet(tmp_path / "sessions.parquet")
    assert dict(zip(sessions["session_id"], sessions["seed"], strict=True)) == db["sessions"]
    trials = pd.read_parquet(tmp_path / "trials.parquet")
    assert sorted(trials["seed"].tolist()) == sorted(db["trials"].values())
    # NA, never -1: no Latin-square row here; generation-0 faces have no parents
    assert sessions["order_row"].isna().all()
    faces = pd.read_parquet(tmp_path / "faces.parquet")
    first = faces["generation"] == 0
    assert faces.loc[first, "parent_a"].isna().all() and faces.loc[~first, "parent_a"].notna().any()
    for name in TABLES:
        df = pd.read_parquet(tmp_path / f"{name}.parquet")
        for c in df.columns:
            if pd.api.types.is_integer_dtype(df[c].dtype):
                assert not (df[c] == -1).any(), (name, c)
            elif (name, c) not in JSON_CELLS and pd.api.types.is_string_dtype(df[c].dtype):
                text = df[c].dropna().astype(str)
                assert not text.str.match(r"^\s*[\[{]").any(), (name, c)  # no JSON in cells
    # the trial order is the trials table, one row per position (no JSON list in sessions)
    assert "trial_order" not in sessions.columns
    for sid, order in db["orders"].items():
        mine = trials[trials["session_id"] == sid].sort_values("trial")
        assert mine["condition"].tolist() == order


def test_csv_export_keeps_seeds_exact_for_r_and_times_with_their_zone(
    service: StudyService, tmp_path: Path, rscript: None
) -> None:
    completed(service, "C-1")
    tables = export_tables(service.store)
    write_export(tables, tmp_path / "csv", "csv")
    write_export(tables, tmp_path / "pq", "parquet")
    db = _seeds(service)
    assert any(s > 2**53 for s in db["sessions"].values())
    in_r = read_in_r([tmp_path / "csv" / "sessions.csv", tmp_path / "csv" / "trials.csv"])
    sessions, trials = (t.frame for t in in_r)
    # read by R's readr, the seed is text, and exact; times are POSIXct in UTC
    assert in_r[0].classes["seed"] == in_r[1].classes["seed"] == "character"
    assert [int(s.removeprefix("s")) for s in sessions["seed"]] == list(db["sessions"].values())
    assert sorted(int(s.removeprefix("s")) for s in trials["seed"]) == sorted(db["trials"].values())
    assert in_r[0].classes["created_at"] == in_r[1].classes["started_at"] == "POSIXct:UTC"
    for stamp in sessions["created_at"].tolist() + trials["started_at"].dropna().tolist():
        assert ISO_UTC.match(stamp), stamp
    assert sessions["user_agent"].isna().all()  # not collected: NA (an empty cell)
    # read back with emogen.columns: the very table the Parquet file holds
    for name in ("sessions", "trials", "faces", "selections"):
        back = tidy.read_csv(tmp_path / "csv" / f"{name}.csv")
        pd.testing.assert_frame_equal(back, pd.read_parquet(tmp_path / "pq" / f"{name}.parquet"))


def test_an_empty_export_has_the_schema_of_a_full_one(
    service: StudyService, tmp_path: Path
) -> None:
    write_export(export_tables(service.store), tmp_path / "empty", "parquet")
    write_export(export_tables(service.store), tmp_path / "empty_csv", "csv")
    completed(service, "E-1", restart=True)  # every table has rows: a restart, a rating
    write_export(export_tables(service.store), tmp_path / "full", "parquet")
    write_export(export_tables(service.store), tmp_path / "full_csv", "csv")
    for name in TABLES:
        empty = pq.read_schema(tmp_path / "empty" / f"{name}.parquet")
        full = pq.read_schema(tmp_path / "full" / f"{name}.parquet")
        assert empty.remove_metadata() == full.remove_metadata(), name
        assert pd.read_parquet(tmp_path / "empty" / f"{name}.parquet").dtypes.equals(
            pd.read_parquet(tmp_path / "full" / f"{name}.parquet").dtypes
        ), name
        head = (tmp_path / "empty_csv" / f"{name}.csv").read_text().splitlines()[0]
        assert head == (tmp_path / "full_csv" / f"{name}.csv").read_text().splitlines()[0]
    arrow = {
        "int": pa.int64(),
        "seed": pa.int64(),
        "float": pa.float64(),
        "str": pa.string(),
        "time": pa.timestamp("us", tz="UTC"),
        "bool": pa.bool_(),
    }
    for name, table in SESSION_TABLES.items():  # each table's declared columns and types
        for folder in ("empty", "full"):
            schema = pq.read_schema(tmp_path / folder / f"{name}.parquet")
            assert schema.names[: len(table.columns)] == table.column_names, (name, folder)
            for column, kind in table.columns:
                assert schema.field(column).type == arrow[kind], (name, column)


def test_every_export_column_is_in_the_data_dictionary(service: StudyService) -> None:
    completed(service, "D-1", restart=True)
    for name, df in export_tables(service.store).items():
        assert not undocumented(list(df.columns), f"study export: {name}"), name
