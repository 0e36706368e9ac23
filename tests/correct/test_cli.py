"""``emogen correct`` through a tiny Typer app (the command is registered in emogen.cli.app)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import typer
from typer.testing import CliRunner

from emogen.cli.correct import correct_command
from emogen.correct import evaluate_corrected

app = typer.Typer()
app.command("correct")(correct_command)
app.command("other")(lambda: None)  # two commands: `correct` stays a subcommand


def test_correct_csv_adds_corrective_columns_and_saves_meshes(
    ict_dir: Path, ict_model, tmp_path: Path
) -> None:
    src = tmp_path / "faces.csv"
    pd.DataFrame(
        {"mouthShrugLower": [1.0, 0.0], "mouthSmile": [0.2, 0.0], "browDown_L": [0.0, 0.5]}
    ).to_csv(src, index=False)
    out, mesh = tmp_path / "out.csv", tmp_path / "out.npz"
    res = CliRunner().invoke(
        app, ["correct", str(src), "--out", str(out), "--mesh", str(mesh), "--model", str(ict_dir)]
    )
    assert res.exit_code == 0, res.output
    assert "1 with a collision, 0 remaining" in res.output
    table = pd.read_csv(out)
    assert list(table.columns[: ict_model.n_shapes]) == list(ict_model.shape_names)
    assert table.loc[0, "mouthSmile_L"] == 0.2 and table.loc[1, "browDown_L"] == 0.5
    assert table.loc[0, "collision_detected"] and not table.loc[0, "collision_remaining"]
    lip = [c for c in table.columns if c.startswith("collision_lip_")]
    assert len(lip) == 4 and table.loc[0, lip].sum() > 0 and table.loc[1, lip].sum() == 0
    z = np.load(mesh)
    assert z["vertices"].shape == (2, ict_model.n_vertices, 3)
    w = table[list(ict_model.shape_names)].to_numpy()
    np.testing.assert_allclose(z["vertices"], evaluate_corrected(ict_model, w), atol=1e-5)


def test_unknown_column_is_an_error_naming_it(ict_dir: Path, tmp_path: Path) -> None:
    src = tmp_path / "faces.csv"
    src.write_text("jawOpen,mouthSmiel\n0.5,0.2\n")
    res = CliRunner().invoke(
        app, ["correct", str(src), "--out", str(tmp_path / "o.csv"), "--model", str(ict_dir)]
    )
    assert res.exit_code == 3  # a data error (docs/cli.md)
    assert "unknown column 'mouthSmiel': did you mean 'mouthSmile'?" in res.output


def test_out_of_range_weight_is_an_error_naming_the_cell(ict_dir: Path, tmp_path: Path) -> None:
    src = tmp_path / "faces.csv"
    src.write_text("jawOpen\n0.5\n1.2\n")
    res = CliRunner().invoke(
        app, ["correct", str(src), "--out", str(tmp_path / "o.csv"), "--model", str(ict_dir)]
    )
    assert res.exit_code == 3
    assert "column 'jawOpen' row 2 (line 3): weight must be in [0, 1]; got '1.2'" in res.output
