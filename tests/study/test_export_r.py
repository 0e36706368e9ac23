"""Study exports and analysis tables as R reads them: real R (Debian's ``r-base-core`` and
``r-cran-readr``, through ``Rscript``; tests/r_readers.py), with ``readr::read_csv``'s defaults
and with the ``col_types.csv`` written beside the tables; docs/data.md's R lines run as written.

The reference for each column's class is the Parquet file of the same export (its Arrow
schema: integers and floats → numeric, text → character, timestamps → POSIXct in UTC,
booleans → logical; seeds, ``s<digits>`` in CSV → character) and, for analysis tables, readr's
own guess from the rows.
"""

from __future__ import annotations

import re
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from sqlalchemy import update
from typer.testing import CliRunner

from emogen.cli.analysis import analysis_app
from emogen.study.export import TABLES, export_tables, write_export
from emogen.study.export_stream import SETTLE, export_study
from emogen.study.sessions import StudyService
from emogen.study.tables import SessionRow
from emogen.tasks.registry import TASKS
from tests.r_readers import DOCS, R_CLASS, RTable, col_types_of, read_in_r, run_r
from tests.study.test_export_replay import completed


@pytest.fixture
def db_url(tmp_path: Path) -> str:
    """One backend is enough: R reads the files, whichever database wrote them."""
    return f"sqlite:///{tmp_path / 'study.sqlite'}"


def r_class(field: pa.Field) -> str:
    """The R class a column of this Arrow type must have (the CSV's seeds are text)."""
    if field.name in ("seed", "run_seed"):
        return "character"
    if pa.types.is_timestamp(field.type):
        return "POSIXct:UTC"
    if pa.types.is_integer(field.type) or pa.types.is_floating(field.type):
        return "numeric"
    return "logical" if pa.types.is_boolean(field.type) else "character"


def guessed_agrees(guess: RTable, want: dict[str, str]) -> list[str]:
    """The columns whose readr guess differs from ``want`` — but for a column with no value,
    which readr reads as logical."""
    return [
        c
        for c, k in guess.classes.items()
        if k != want[c] and not (k == "logical" and guess.frame[c].isna().all())
    ]


def test_every_export_table_reads_in_r_with_its_types(
    service: StudyService, tmp_path: Path, rscript: None
) -> None:
    completed(service, "R-1", restart=True)
    completed(service, "R-2")
    export_study(service.store, tmp_path / "csv", "csv")  # what `emogen study export` writes
    tables = export_tables(service.store)
    write_export(tables, tmp_path / "mem", "csv")
    write_export(tables, tmp_path / "pq", "parquet")
    types = col_types_of(tmp_path / "csv")
    assert types == col_types_of(tmp_path / "mem") and sorted(types) == sorted(TABLES)
    paths = [tmp_path / "csv" / f"{name}.csv" for name in TABLES]
    guessed, given = read_in_r(paths), read_in_r(paths, types)
    empty = [name for name in TABLES if len(tables[name]) == 0]
    others = [
        t.name for task in TASKS.values() if task.name != "evolve" for t in task.export_tables
    ]
    # an evolve study without a dynamic block: its face_curves and the other tasks' tables
    assert sorted(empty) == sorted(["face_curves", *others])
    final = given[TABLES.index("final_faces")]  # a finished trial's final face, typed in R
    assert len(final.frame) == 4 and final.frame["face_id"].notna().all()
    assert {final.classes[c] for c in ("session_id", "trial", "attempt", "face_id")} == {"numeric"}
    assert final.classes["emotion"] == "character"
    assert final.classes["finished_at"] == "POSIXct:UTC"
    gene_classes = {k for c, k in final.classes.items() if c.startswith(("g_", "w_"))}
    assert gene_classes == {"numeric"}
    for name, guess, read in zip(TABLES, guessed, given, strict=True):
        parquet = tmp_path / "pq" / f"{name}.parquet"
        want = {f.name: r_class(f) for f in pq.read_schema(parquet)}
        assert read.classes == want, name
        assert read.problems == 0 and len(read.frame) == len(tables[name]), name
        if name in empty:  # readr has no rows to guess from: all text, hence col_types.csv
            assert set(guess.classes.values()) == {"character"}
            continue
        assert not guessed_agrees(guess, want), (name, guessed_agrees(guess, want))
        # the values too: those of the Parquet file
        ref = pd.read_parquet(parquet)
        for c, k in read.classes.items():
            got, exp = read.frame[c], ref[c]
            if k == "numeric":  # readr's own number parser: the last bits may differ
                want_values = exp.astype("float64").to_numpy()
                np.testing.assert_allclose(got.to_numpy(), want_values, rtol=1e-12, atol=0)
            elif c in ("seed", "run_seed"):
                assert got.tolist() == [f"s{int(v)}" for v in exp], (name, c)
            elif k == "POSIXct:UTC":  # R's POSIXct (seconds, a double): within 1 µs
                back = pd.to_datetime(got, utc=True, format="ISO8601")
                assert (back.isna() == exp.isna()).all(), (name, c)
                gap = (back - exp).abs().dropna()
                assert (gap <= pd.Timedelta(microseconds=1)).all(), (name, c, gap.max())


def r_block(text: str) -> str:
    """docs/data.md's R code (its ```r block), as written."""
    blocks = re.findall(r"^( *)```r\n(.*?)^\1```", text, re.M | re.S)
    assert len(blocks) == 1, f"docs/data.md should have one R block; found {len(blocks)}"
    indent, code = blocks[0]
    return "\n".join(line.removeprefix(indent) for line in code.splitlines()) + "\n"


def test_the_r_lines_of_the_data_dictionary_append_incremental_exports(
    service: StudyService, tmp_path: Path, rscript: None
) -> None:
    completed(service, "B-1")
    completed(service, "B-2", restart=True)
    t0 = datetime(2026, 5, 1, 12, 0, tzinfo=UTC)
    with service.store.write() as db:
        for sid, minutes in ((1, 0), (2, 10)):
            db.execute(update(SessionRow).where(SessionRow.id == sid)
                       .values(completed_at=t0 + timedelta(minutes=minutes)))  # fmt: skip
    first = export_study(service.store, tmp_path / "export-1", "csv", since=t0 - timedelta(days=1),
                         now=t0 + timedelta(minutes=5) + SETTLE)  # fmt: skip
    export_study(service.store, tmp_path / "export-2", "csv", since=first.until,
                 now=t0 + timedelta(hours=1))  # fmt: skip
    assert (first.rows["restarts"], first.rows["categorise_responses"]) == (
        0,
        0,
    )  # header-only files
    write_export(export_tables(service.store), tmp_path / "pq", "parquet")
    checks = """
    responses <- rbind(read_emogen("export-1", "categorise_responses"),
                   read_emogen("export-2", "categorise_responses"))
    for (d in list(restarts, responses)) {
      cat(nrow(d), paste(names(d), vapply(d, function(x) class(x)[1], ""), sep = "=",
          collapse = " "), "\\n")
    }
    cat(seeds, "\\n")
    """
    out = run_r(r_block(DOCS.read_text(encoding="utf-8")) + checks, tmp_path).splitlines()
    for line, name, rows in ((out[0], "restarts", 1), (out[1], "categorise_responses", 0)):
        n, *columns = line.split()
        classes = dict(c.split("=") for c in columns)
        want = {
            f.name: r_class(f).split(":")[0]
            for f in pq.read_schema(tmp_path / "pq" / f"{name}.parquet")
        }
        assert int(n) == rows and classes == want, (name, line)
    trials = pd.read_parquet(tmp_path / "pq" / "trials.parquet")
    mine = trials[trials["session_id"] == 1]["seed"]
    assert out[2].split() == [str(int(s)) for s in mine]  # exact


def test_every_analysis_table_reads_in_r_as_written(
    service: StudyService, tmp_path: Path, ict_dir: Path, rscript: None
) -> None:
    for p in ("A-1", "A-2", "A-3"):
        completed(service, p, restart=p == "A-1")
    write_export(export_tables(service.store), tmp_path / "export", "csv")
    result = CliRunner().invoke(
        analysis_app,
        [
            "analyse",
            str(tmp_path / "export"),
            "--out",
            str(tmp_path / "report"),
            "--model",
            str(ict_dir),
            "--no-render",
        ],
    )
    assert result.exit_code == 0, result.output
    folder = tmp_path / "report" / "tables"
    paths = sorted(p for p in folder.glob("*.csv") if p.name != "col_types.csv")
    types = col_types_of(folder)
    assert sorted(types) == [p.stem for p in paths] and len(paths) >= 8
    for path, guess, read in zip(paths, read_in_r(paths), read_in_r(paths, types), strict=True):
        want = {c: R_CLASS[k] for c, k in zip(read.classes, types[path.stem], strict=True)}
        assert {c: k.split(":")[0] for c, k in read.classes.items()} == want, path.name
        assert read.problems == 0, path.name
        if len(guess.frame):  # readr's own guess from the rows agrees
            assert not guessed_agrees(guess, read.classes), (path.name, guess.classes)
