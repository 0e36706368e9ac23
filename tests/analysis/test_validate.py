"""Analysis inputs are checked before anything is computed: a hand-edited or broken export is
one data error naming the table, column, row and value, never a quiet analysis or a KeyError."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.analysis.data import load_dataset
from emogen.cli import app
from emogen.errors import DataError


def _study(folder: Path, fmt: str = "csv") -> dict[str, pd.DataFrame]:
    """A small, valid study export written by hand: 2 participants x 1 trial x 2 generations."""
    trials = pd.DataFrame(
        {
            "session_id": [1, 2],
            "participant_id": ["P1", "P2"],
            "trial": [0, 0],
            "emotion": ["happy", "happy"],
            "status": ["done", "done"],
        }
    )
    rng = np.random.default_rng(3)
    faces = pd.DataFrame(
        [
            {
                "session_id": s,
                "trial": 0,
                "attempt": 0,
                "generation": g,
                "face_id": f,
                "w_jawOpen": rng.uniform(),
                "w_mouthSmile_L": rng.uniform(),
            }
            for s in (1, 2)
            for g in (0, 1)
            for f in range(3)
        ]
    )
    selections = pd.DataFrame(
        [
            {
                "session_id": s,
                "trial": 0,
                "attempt": 0,
                "generation": g,
                "face_id": 0,
                "role": "elite",
            }
            for s in (1, 2)
            for g in (0, 1)
        ]
    )
    tables = {"trials": trials, "faces": faces, "selections": selections}
    write(folder, tables, fmt)
    return tables


def write(folder: Path, tables: dict[str, pd.DataFrame], fmt: str) -> None:
    folder.mkdir(exist_ok=True)
    for name, df in tables.items():
        df.to_csv(folder / f"{name}.csv", index=False) if fmt == "csv" else df.to_parquet(
            folder / f"{name}.parquet"
        )


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_wrong_values_in_an_export_are_named(tmp_path: Path, fmt: str) -> None:
    folder = tmp_path / "export"
    tables = _study(folder, fmt)
    assert load_dataset(folder).kind == "study"  # the valid export loads

    def fails(name: str, column: str, row: int, value: object, message: str) -> None:
        broken = {k: v.copy() for k, v in tables.items()}
        text = fmt == "parquet" and isinstance(value, str)  # Parquet: a column of one type
        broken[name][column] = broken[name][column].astype(str if text else object)
        broken[name].loc[row, column] = value
        write(folder, broken, fmt)
        with pytest.raises(DataError) as info:
            load_dataset(folder)
        assert message in str(info.value), str(info.value)
        assert "np." not in str(info.value)

    fails("faces", "w_jawOpen", 4, 1.7, "faces: column 'w_jawOpen' row 5: weight must be in [0, 1]")
    fails("faces", "w_jawOpen", 0, np.nan, "faces: column 'w_jawOpen' row 1: empty or missing")
    fails("faces", "w_jawOpen", 2, "lots", "column 'w_jawOpen' row 3: 'lots' is not a number")
    fails("faces", "generation", 1, 0.5, "column 'generation' row 2: 0.5 is not a whole number")
    fails("trials", "session_id", 1, "x", "trials: column 'session_id' row 2: 'x' is not a number")
    fails("selections", "role", 0, None, "selections: column 'role' row 1: empty")


def test_an_empty_trials_table_is_a_clear_error(tmp_path: Path) -> None:
    folder = tmp_path / "export"
    tables = _study(folder)
    tables["trials"].iloc[:0].to_csv(folder / "trials.csv", index=False)
    with pytest.raises(DataError, match=r"trials has no rows: no trials to analyse"):
        load_dataset(folder)
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["analyse", str(folder), "--out", str(out)])
    assert result.exit_code == 3 and "trials has no rows" in result.output
    assert "KeyError" not in result.output and not out.exists()


def test_a_simulation_with_nan_errors_or_bad_weights_is_refused(tmp_path: Path) -> None:
    sim = tmp_path / "sim"
    sim.mkdir()
    (sim / "simulation.json").write_text(json.dumps({"config": {}, "target_weights": {}}))
    table = pd.DataFrame(
        {
            "run": [0, 0],
            "generation": [0, 1],
            "elite_error": [0.4, 0.2],
            "elite_distance": [0.4, 0.2],
            "n_selected": [2, 2],
            "run_seed": [1, 1],
        }
    )
    table.to_parquet(sim / "simulation.parquet")
    assert load_dataset(sim).kind == "simulation"
    table.assign(elite_error=[0.4, np.nan]).to_parquet(sim / "simulation.parquet")
    with pytest.raises(DataError, match=r"simulation: column 'elite_error' row 2: empty"):
        load_dataset(sim)
    table.to_parquet(sim / "simulation.parquet")
    faces = pd.DataFrame(
        {
            "run": [0],
            "generation": [1],
            "slot": [0],
            "operator": ["S"],
            "distance": [0.1],
            "error": [0.2],
            "rank": [0],
            "jawOpen": [1.7],
        }
    )
    faces.to_parquet(sim / "faces.parquet")
    with pytest.raises(DataError, match=r"faces: column 'jawOpen' row 1: .* got 1.7$"):
        load_dataset(sim)
