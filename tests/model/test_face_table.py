"""The one face-table reader, against a plain csv/pandas reading of the same small files."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from emogen.errors import ConfigError, DataError
from emogen.model.face_table import read_face_table
from emogen.model.rig import Rig
from emogen.model.rig_build import build_rig
from emogen.model.rig_spec import RigSpec

SHAPES = ("jawOpen", "mouthSmile_L", "mouthSmile_R", "eyeBlink_L", "eyeBlink_R")
#: The rig's genes written out by hand: a pair is one gene.
GENES = {
    "jawOpen": ["jawOpen"],
    "mouthSmile": ["mouthSmile_L", "mouthSmile_R"],
    "eyeBlink": ["eyeBlink_L", "eyeBlink_R"],
}


@pytest.fixture
def rig() -> Rig:
    return build_rig(RigSpec(name="tiny"), SHAPES, "(test)")


def expected_from_csv(path: Path) -> np.ndarray:
    """The reference: the csv module and a loop over cells, later columns overwriting."""
    with path.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    out = np.zeros((len(rows), len(SHAPES)))
    for i, row in enumerate(rows):
        for key, value in row.items():
            for shape in GENES.get(key, [key] if key in SHAPES else []):
                out[i, SHAPES.index(shape)] = float(value)
    return out


def test_csv_with_other_columns_matches_a_plain_reading(rig: Rig, tmp_path: Path) -> None:
    path = tmp_path / "faces.csv"
    path.write_text(
        "run,jawOpen,mouthSmile,eyeBlink_R,note\n0,0.5,0.25,1,a\n1,0,1,0.125,b\n2,1,0,0,c\n"
    )
    table = read_face_table(path, rig)
    np.testing.assert_array_equal(table.weights, expected_from_csv(path))
    assert table.columns == ("jawOpen", "mouthSmile", "eyeBlink_R")
    assert list(table.frame["run"]) == [0, 1, 2]
    q = read_face_table(path, rig, query="run >= 1")
    np.testing.assert_array_equal(q.weights, expected_from_csv(path)[1:])


def test_parquet_matches_pandas(rig: Rig, tmp_path: Path) -> None:
    frame = pd.DataFrame({"mouthSmile_L": [0.1, 0.9], "jawOpen": [0.3, 0.0], "generation": [4, 5]})
    path = tmp_path / "faces.parquet"
    frame.to_parquet(path)
    reference = pd.read_parquet(path)
    w = read_face_table(path, rig).weights
    assert w.shape == (2, len(SHAPES))
    np.testing.assert_array_equal(w[:, SHAPES.index("mouthSmile_L")], reference["mouthSmile_L"])
    np.testing.assert_array_equal(w[:, SHAPES.index("jawOpen")], reference["jawOpen"])
    assert not w[:, [SHAPES.index("mouthSmile_R"), SHAPES.index("eyeBlink_L")]].any()


def test_weights_only_csv_with_labels_and_blank_cells(rig: Rig, tmp_path: Path) -> None:
    path = tmp_path / "faces.csv"
    path.write_text("\ufefflabel, mouthSmile,mouthSmile_L\nhappy,0.5,\n\n,,0.75\n")
    table = read_face_table(
        path, rig, others="error", label_columns=("label",), blank="zero", unit_range=True
    )
    assert table.labels == ("happy", "")
    expected = np.zeros((2, len(SHAPES)))
    expected[0, [1, 2]] = 0.5  # the empty mouthSmile_L cell leaves the gene's value
    expected[1, 1] = 0.75
    np.testing.assert_array_equal(table.weights, expected)
    assert np.isnan(table.values[1, 0]) and table.values[1, 1] == 0.75


def test_unknown_shape_column_is_named(rig: Rig, tmp_path: Path) -> None:
    path = tmp_path / "faces.csv"
    path.write_text("jawOpen,mouthSmiel\n0.5,0.2\n")
    with pytest.raises(DataError, match=r"faces\.csv: unknown column 'mouthSmiel'.*mouthSmile"):
        read_face_table(path, rig, others="error")
    path.write_text("run,score\n1,2\n")
    with pytest.raises(ConfigError, match="no column is a shape or gene name of rig 'tiny'"):
        read_face_table(path, rig)


@pytest.mark.parametrize("others", ["ignore", "error"])
def test_non_numeric_value_names_file_column_row_and_value(
    rig: Rig, tmp_path: Path, others: str
) -> None:
    path = tmp_path / "faces.csv"
    path.write_text("jawOpen,eyeBlink\n0.5,0\n0.25,lots\n")
    with pytest.raises(ConfigError, match=r"faces\.csv: column 'eyeBlink' row 2.*'lots' is not a"):
        read_face_table(path, rig, others=others)  # type: ignore[arg-type]


def test_weights_only_csv_errors(rig: Rig, tmp_path: Path) -> None:
    path = tmp_path / "faces.csv"

    def fails(text: str, error: type[Exception], match: str, **kw: object) -> None:
        path.write_text(text)
        with pytest.raises(error, match=match):
            read_face_table(path, rig, what="--weights", others="error", **kw)  # type: ignore[arg-type]

    fails("jawOpen\n0.5\nNA\n", ConfigError, r"row 2 \(line 3\): 'NA' is not a number")
    fails(
        "jawOpen\n1.5\n",
        ConfigError,
        r"row 1 \(line 2\): weight must be in \[0, 1\]",
        unit_range=True,
    )
    fails("jawOpen\ninf\n", ConfigError, "'inf' is not a finite number")
    fails("jawOpen\n0.5,1\n", ConfigError, r"--weights .*faces\.csv line 2: 2 values")
    fails("jawOpen,jawOpen\n0.5,1\n", ConfigError, r"\['jawOpen'\] appear more than once")
    fails("jawOpen,eyeBlink\n0.5,\n", ConfigError, "column 'eyeBlink' row 1 .*empty")


@pytest.mark.parametrize("others", ["ignore", "error"])
@pytest.mark.parametrize("text", ["", "jawOpen\n"])
def test_empty_file_is_an_error(rig: Rig, tmp_path: Path, others: str, text: str) -> None:
    path = tmp_path / "faces.csv"
    path.write_text(text)
    with pytest.raises(ConfigError, match=r"faces\.csv (is empty|has no rows)"):
        read_face_table(path, rig, others=others)  # type: ignore[arg-type]


def test_missing_file_and_wrong_suffix(rig: Rig, tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"nope\.csv does not exist"):
        read_face_table(tmp_path / "nope.csv", rig)
    with pytest.raises(ConfigError, match=r"nope\.csv does not exist"):
        read_face_table(tmp_path / "nope.csv", rig, others="error")
    with pytest.raises(ConfigError, match=r"expected a \.parquet or \.csv file; got '\.txt'"):
        read_face_table(tmp_path / "faces.txt", rig)


# ---- one set of rules for every reader ---------------------------------------------------
@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_a_misspelt_shape_column_is_never_dropped(rig: Rig, tmp_path: Path, suffix: str) -> None:
    # a simulation's faces table keeps its bookkeeping columns, but 'jawOpn' is a typo
    frame = pd.DataFrame({"run": [0], "rank": [0], "jawOpn": [0.7], "mouthSmile": [0.2]})
    path = tmp_path / f"faces{suffix}"
    frame.to_csv(path, index=False) if suffix == ".csv" else frame.to_parquet(path)
    with pytest.raises(DataError, match=r"unknown column 'jawOpn': did you mean 'jawOpen'\?"):
        read_face_table(path, rig)
    frame.rename(columns={"jawOpn": "jaw_open"}).to_csv(tmp_path / "sep.csv", index=False)
    with pytest.raises(DataError, match=r"unknown column 'jaw_open': did you mean 'jawOpen'\?"):
        read_face_table(tmp_path / "sep.csv", rig)
    frame.rename(columns={"jawOpn": "notes"}).to_csv(tmp_path / "ok.csv", index=False)
    assert read_face_table(tmp_path / "ok.csv", rig).weights[0, 1] == 0.2  # other columns: kept


@pytest.mark.parametrize("others", ["ignore", "error"])
@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_out_of_range_weights_are_errors_everywhere_in_one_format(
    rig: Rig, tmp_path: Path, others: str, suffix: str
) -> None:
    if others == "error" and suffix == ".parquet":
        pytest.skip("weights-only tables are CSV")
    frame = pd.DataFrame({"jawOpen": [0.5, 0.25, 1.7]})
    path = tmp_path / f"faces{suffix}"
    frame.to_csv(path, index=False) if suffix == ".csv" else frame.to_parquet(path)
    line = " (line 4)" if others == "error" else ""
    with pytest.raises(DataError) as info:
        read_face_table(path, rig, others=others)  # type: ignore[arg-type]
    # row 3 = the third row after the header; the value as written, not np.float64(1.7)
    expected = f"column 'jawOpen' row 3{line}: weight must be in [0, 1]; got "
    assert expected in str(info.value) and "np." not in str(info.value)
    assert str(info.value).endswith(("'1.7'", "1.7"))
