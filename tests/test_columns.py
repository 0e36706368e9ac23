"""The output rules themselves (emogen.columns), against pandas and pyarrow reading the files."""

from __future__ import annotations

import io
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from emogen import columns as tidy
from emogen.errors import ConfigError
from tests.r_readers import R_CLASS, col_types_of, read_in_r

BIG = 2**60 + 1  # no double holds it: float(BIG) == 2**60


def test_a_big_seed_beside_a_missing_value_survives_csv_and_parquet(
    tmp_path: Path, rscript: None
) -> None:
    rows = [
        {"seed": BIG, "rank": 0, "shown_at": "2026-01-31T09:30:00+00:00"},
        {"seed": None, "rank": None, "shown_at": None},
    ]
    df = tidy.frame(rows)
    assert df["seed"].iloc[0] == BIG and df["seed"].isna().iloc[1]
    tidy.write_csv(df, tmp_path / "t.csv")
    # the plain digits would have been rounded: pandas (a missing value makes the column
    # float) and R (every numeric column is double) both lose the last bits
    assert int(pd.read_csv(io.StringIO(f"seed,x\n{BIG},1\n,2\n"))["seed"].iloc[0]) != BIG
    (as_r,) = read_in_r([tmp_path / "t.csv"])  # R's readr, its defaults
    assert as_r.classes["seed"] == "character" and as_r.problems == 0
    assert as_r.frame["seed"].iloc[0] == f"s{BIG}" and pd.isna(as_r.frame["seed"].iloc[1])
    assert as_r.classes["rank"] == "numeric" and as_r.frame["rank"].isna().iloc[1]  # NA, not -1
    assert as_r.classes["shown_at"] == "POSIXct:UTC"
    assert as_r.frame["shown_at"].iloc[0] == "2026-01-31T09:30:00.000000Z"
    back = tidy.read_csv(tmp_path / "t.csv")
    pd.testing.assert_frame_equal(back, df)
    tidy.write_parquet(df, tmp_path / "t.parquet", {"seed": BIG})
    schema = pq.read_schema(tmp_path / "t.parquet")
    assert schema.field("seed").type == pa.int64()
    assert schema.field("shown_at").type == pa.timestamp("us", tz="UTC")
    assert pd.read_parquet(tmp_path / "t.parquet")["seed"].iloc[0] == BIG
    assert tidy.provenance(tmp_path / "t.parquet")["seed"] == BIG


def test_empty_tables_take_their_columns_types() -> None:
    empty = tidy.typed(pd.DataFrame(), ["seed", "created_at", "rank", "study", "w_jawOpen"])
    full = tidy.typed(
        pd.DataFrame(
            {
                "seed": [1],
                "created_at": ["2026-01-01T00:00:00Z"],
                "rank": [0],
                "study": ["s"],
                "w_jawOpen": [0.5],
            }
        )
    )
    assert empty.dtypes.equals(full.dtypes)
    assert (
        tidy.arrow_table(empty).schema.remove_metadata()
        == tidy.arrow_table(full).schema.remove_metadata()
    )


def test_an_empty_table_reads_in_r_with_the_types_of_a_full_one(
    tmp_path: Path, rscript: None
) -> None:
    """readr guesses types from rows: a table without rows reads as all text unless given its
    ``col_types`` (col_types.csv, written beside the table)."""
    rows = [
        {
            "seed": BIG,
            "rank": 1,
            "shown_at": "2026-01-31T09:30:00Z",
            "study": "s",
            "w_jawOpen": 0.5,
            "correct": True,
            "p_value": 0.04,
            "note": "x",
        }
    ]
    full = tidy.frame(rows)
    empty = tidy.typed(full.iloc[:0])
    for name, df in (("full", full), ("empty", empty)):
        (tmp_path / name).mkdir()
        tidy.write_csv(df, tmp_path / name / "t.csv", col_types=True)
    types = col_types_of(tmp_path / "empty")
    assert types == col_types_of(tmp_path / "full") == {"t": "cdTcdldc"}
    as_guessed, as_given, empty_given = read_in_r(
        [tmp_path / "full" / "t.csv", tmp_path / "full" / "t.csv", tmp_path / "empty" / "t.csv"],
        [{}, types, types],
    )
    want = {
        "seed": "character",
        "rank": "numeric",
        "shown_at": "POSIXct:UTC",
        "study": "character",
        "w_jawOpen": "numeric",
        "correct": "logical",
        "p_value": "numeric",
        "note": "character",
    }
    assert as_guessed.classes == as_given.classes == empty_given.classes == want
    assert {R_CLASS[k] for k in types["t"]} <= {c.split(":")[0] for c in want.values()}
    assert len(empty_given.frame) == 0 and empty_given.problems == 0


def test_values_that_do_not_fit_their_type_are_named() -> None:
    with pytest.raises(ConfigError, match="column 'rank'"):
        tidy.typed(pd.DataFrame({"rank": ["1.5"]}))
    with pytest.raises(ConfigError, match="column 'seed'"):
        tidy.typed(pd.DataFrame({"seed": ["s12x"]}))


@pytest.mark.parametrize(
    ("header", "name"),
    [
        ("bias mean", "bias_mean"),
        ("max [cm]", "max_cm"),
        ("[0.25, 0.5) %", "x0_25_0_5_pct"),
        ("GA noise μ ± σ", "ga_noise_mean_pm_sd"),
        ("w_jawOpen", "w_jawOpen"),
        ("classified as →", "classified_as"),
    ],
)
def test_machine_names(header: str, name: str) -> None:
    assert tidy.machine_name(header) == name


def test_matrices_are_written_long() -> None:
    matrix = pd.DataFrame(
        [[3, 1], [0, 4]], index=pd.Index(["a", "b"], name="group"), columns=["c1", "c2"]
    )
    matrix.columns.name = "cluster"
    long = tidy.machine_table(matrix, index=True)
    assert list(long.columns) == ["group", "cluster", "entry"]
    assert sorted(map(tuple, long.to_numpy().tolist())) == [
        ("a", "c1", 3),
        ("a", "c2", 1),
        ("b", "c1", 0),
        ("b", "c2", 4),
    ]
    shown = pd.DataFrame({"group": ["a"], "participants": ["–"], "bias mean": [0.5]})
    out = tidy.machine_table(shown)
    assert list(out.columns) == ["group", "participants", "bias_mean"]
    assert out["participants"].isna().all()


def test_git_commit_is_this_checkout_or_none() -> None:
    commit = tidy.git_commit()
    assert commit is None or (len(commit) == 40 and int(commit, 16) >= 0)
