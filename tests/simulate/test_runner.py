"""Simulation runs: the tidy table, the record, determinism, and `emogen simulate`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
from typer.testing import CliRunner

from emogen.cli import app
from emogen.config import GAConfig, InitConfig, SimulationConfig
from emogen.rng import spawn_seeds
from emogen.simulate.runner import COLUMNS, run_simulation, simulate_run, write_simulation

runner = CliRunner()


def test_table_and_record(ict_model, tmp_path: Path) -> None:
    cfg = SimulationConfig(target={"jawOpen": 0.8}, runs=6, seed=1)
    result = run_simulation(cfg, ict_model.rig, model_name="ict", model_hash=ict_model.model_hash)
    t = result.table
    assert tuple(t.columns) == COLUMNS and len(t) == 6 * 11
    assert t["run"].tolist() == np.repeat(np.arange(6), 11).tolist()
    assert t["generation"].tolist() == list(range(11)) * 6
    assert t["n_selected"].tolist()[:11] == [2, 4, 4, 4, 4, 4, 5, 5, 5, 5, 1]
    assert t["elite_error"].between(0, 1).all()
    assert (t["run_seed"].unique() == np.array(spawn_seeds(1, 6))).all()
    rec = result.record
    assert rec["seed"] == 1 and rec["config"]["seed"] == 1 and rec["run_seeds"] == spawn_seeds(1, 6)
    assert rec["config"]["ga"]["mutation_genes"] == 2
    assert rec["target_weights"] == {"jawOpen": 0.8}
    assert rec["model"]["hash"] == ict_model.model_hash
    # each run is simulate_run with its spawned seed
    target = ict_model.rig.weights_from_names({"jawOpen": 0.8})
    errors, _ = simulate_run(cfg, ict_model.rig, target, spawn_seeds(1, 6)[4])
    np.testing.assert_array_equal(errors, t.loc[t["run"] == 4, "elite_error"].to_numpy())
    # the elite never gets worse: it is kept in slot 1
    wide = t.pivot(index="run", columns="generation", values="elite_error").to_numpy()
    assert np.all(np.diff(wide, axis=1) <= 1e-12)
    paths = write_simulation(result, tmp_path / "out")
    pd.testing.assert_frame_equal(pd.read_parquet(paths[0]), t)
    pd.testing.assert_frame_equal(pd.read_csv(paths[1]), t)
    assert json.loads(paths[2].read_text())["seed"] == 1


def test_same_seed_same_table_and_no_seed_is_recorded(ict_model) -> None:
    cfg = SimulationConfig(
        target={"mouthSmile": 0.5, "browInnerUp": 0.4},
        runs=3,
        seed=9,
        ga=GAConfig(eye_motion=False, init=InitConfig(kind="fixed")),
    )
    a = run_simulation(cfg, ict_model.rig).table
    b = run_simulation(cfg, ict_model.rig).table
    pd.testing.assert_frame_equal(a, b)
    free = run_simulation(cfg.model_copy(update={"seed": None}), ict_model.rig)
    assert (
        isinstance(free.record["seed"], int)
        and free.record["config"]["seed"] == free.record["seed"]
    )


def test_cli_simulate(ict_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "sim"
    args = ["simulate", "--model", str(ict_dir), "--target", "jawOpen=0.8", "--target"]
    args += [
        "noseSneer=0.3",
        "--runs",
        "4",
        "--seed",
        "1",
        "--init-range",
        "1-3",
        "--out",
        str(out),
    ]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "generation   0" in result.output and "generation  10" in result.output
    table = pd.read_parquet(out / "simulation.parquet")
    assert len(table) == 44 and set(table.columns) == set(COLUMNS)
    assert (out / "simulation.csv").is_file()
    record = json.loads((out / "simulation.json").read_text())
    assert record["config"]["ga"]["init"]["activation_range"] == [1, 3]
    assert record["config"]["target"] == {"jawOpen": 0.8, "noseSneer": 0.3}


def test_cli_simulate_with_config_file(ict_dir: Path, tmp_path: Path) -> None:
    cfg = tmp_path / "sim.toml"
    cfg.write_text(
        "runs = 2\nseed = 3\ntarget = {mouthSmile = 0.6}\n[ga]\ngenerations = 4\n"
        "[ga.init]\nkind = 'fixed'\n"
    )
    out = tmp_path / "sim"
    result = runner.invoke(
        app, ["simulate", "--model", str(ict_dir), "--config", str(cfg), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    record = json.loads((out / "simulation.json").read_text())
    assert record["config"]["ga"]["generations"] == 4 and record["config"]["runs"] == 2
    assert len(pd.read_csv(out / "simulation.csv")) == 10


def test_cli_simulate_errors(ict_dir: Path, tmp_path: Path) -> None:
    base = ["simulate", "--model", str(ict_dir), "--out", str(tmp_path / "x")]
    cases = [
        (["--target", "jawOpen"], "--target must look like NAME=VALUE"),
        (["--target", "jawOpn=0.5"], "unknown shape or gene 'jawOpn'"),
        (["--target", "jawOpen=0.5", "--init-range", "3to8"], "--init-range must look like LO-HI"),
        (["--target", "jawOpen=0.5", "--init-range", "8-3"], "activation_range must be"),
        (["--target", "jawOpen=0.5", "--runs", "0"], "'runs' must be >= 1"),
        ([], "'target' Field required"),
    ]
    for extra, message in cases:
        result = runner.invoke(app, base + extra)
        assert result.exit_code == 2, (extra, result.output)
        assert message in result.output, (extra, result.output)
    bad = tmp_path / "bad.toml"
    bad.write_text("target = {jawOpen = 1}\n[ga]\nmutaton_genes = 3\n")
    result = runner.invoke(app, [*base, "--config", str(bad)])
    assert result.exit_code == 2 and "unknown key 'mutaton_genes' in [ga]" in result.output
