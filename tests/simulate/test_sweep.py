"""Sweeps: the grid, one job, resumable, each cell written as it finishes; `emogen sweep`."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

import emogen.simulate.sweep as sweep_module
from emogen.cli import app
from emogen.errors import ConfigError
from emogen.simulate.sweep import load_sweep, run_sweep

SWEEP = """
runs = 6
seed = 2
[ga]
generations = 3
[targets]
one = {jawOpen = 1.0}
file = {file = "target.csv", row = 1}
[grid]
metrics = ["cd", "ed"]
init = ["protocol", "fixed"]
variants = ["emogen", "classical"]
[grid.selections]
paper = [2, 4, 4, 4, 4, 4, 5, 5, 5, 5, 5]
three = [3]
"""


@pytest.fixture
def sweep_file(tmp_path: Path) -> Path:
    pd.DataFrame({"jawOpen": [0.1, 0.9], "noseSneer": [0.0, 0.4]}).to_csv(
        tmp_path / "target.csv", index=False
    )
    path = tmp_path / "sweep.toml"
    path.write_text(SWEEP)
    return path


def test_grid_cells(sweep_file: Path) -> None:
    sweep = load_sweep(sweep_file)
    # 2 targets × 2 metrics × 2 inits × (2 schedules for emogen + 1 ranking for classical)
    assert len(sweep.cells) == 24
    cell = next(c for c in sweep.cells if c.name == "file__ed__fixed__three__emogen")
    assert cell.config.selections == (3,) and cell.config.metric.name == "ed"
    assert cell.config.ga.init.kind == "fixed" and cell.config.target_row == 1
    assert cell.config.target_file == sweep_file.parent / "target.csv"  # relative to the sweep
    assert sum(c.labels["schedule"] == "ranking" for c in sweep.cells) == 8


def test_runs_resumes_and_reruns_only_changed_cells(
    ict_model, sweep_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "out"
    sweep = load_sweep(sweep_file)
    written: list[str] = []
    real = sweep_module.write_simulation

    def spy(result, folder, **kw):
        written.append(result.record["cell"])
        return real(result, folder, **kw)

    monkeypatch.setattr(sweep_module, "write_simulation", spy)
    first = run_sweep(sweep, ict_model.rig, out, model_hash="h")
    assert len(first.ran) == 24 and not first.skipped and len(written) == 24
    cell = out / "cells" / "one__cd__protocol__paper__emogen"
    table = pd.read_parquet(cell / "simulation.parquet")
    assert len(table) == 6 * 4 and (cell / "faces.parquet").is_file()
    record = json.loads((cell / "simulation.json").read_text())
    assert record["labels"]["metric"] == "cd" and len(record["config_hash"]) == 64
    summary = pd.read_csv(out / "summary.csv")
    assert len(summary) == 24 and {"mu_0", "mu_final", "sigma_final"} <= set(summary.columns)
    # resume: nothing to do
    written.clear()
    again = run_sweep(sweep, ict_model.rig, out, model_hash="h")
    assert not again.ran and len(again.skipped) == 24 and not written
    # an interrupted cell (no record) and a changed target file re-run; the rest are kept
    (out / "cells" / "one__ed__fixed__three__emogen" / "simulation.json").unlink()
    (sweep_file.parent / "target.csv").write_text("jawOpen,noseSneer\n0.1,0\n0.8,0.5\n")
    third = run_sweep(load_sweep(sweep_file), ict_model.rig, out, model_hash="h")
    assert len(third.ran) == 13 and "one__ed__fixed__three__emogen" in third.ran
    assert all(n.startswith("file__") for n in third.ran if n != "one__ed__fixed__three__emogen")
    # another model: every cell again
    assert len(run_sweep(sweep, ict_model.rig, out, model_hash="other").ran) == 24
    assert not list((out / "cells").glob(".*"))  # no temporary folders left


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[targets]\none = {jawOpen = 1}\n", "needs a seed"),
        ("seed = 1\n", r"\[targets\] must name at least one target"),
        (
            "seed = 1\ntarget = {jawOpen = 1}\n[targets]\na = {jawOpen = 1}\n",
            "'target' is set per cell",
        ),
        ("seed = 1\n[targets]\n'a b' = {jawOpen = 1}\n", "names must use letters"),
        ("seed = 1\n[targets]\na = {jawOpen = 1}\n[grid]\nmetrics = ['cosine']\n", "metrics"),
        ("seed = 1\n[targets]\na = {jawOpen = 2}\n", "must be <= 1"),
        ("seed = 1\n[targets]\na = {file = 'x.csv', weight = 1}\n", "has file and"),
    ],
)
def test_sweep_errors(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_sweep(path)


def test_cli_sweep(ict_dir: Path, sweep_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "cli"
    args = ["sweep", str(sweep_file), "--out", str(out), "--model", str(ict_dir), "--no-progress"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "24 cells: ran 24, skipped 0" in result.output and (out / "summary.csv").is_file()
    result = CliRunner().invoke(app, args)
    assert "ran 0, skipped 24" in result.output
