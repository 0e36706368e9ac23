"""Simulation runs: the tidy table, the record, determinism, and `emogen simulate`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
from typer.testing import CliRunner

from emogen import columns as tidy
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
    pd.testing.assert_frame_equal(tidy.read_csv(paths[1]), t)
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
        (["--target", "jawOpen=0.5", "--runs", "0"], "must be at least 1; got 0"),
        ([], "'target' is required"),
    ]
    for extra, message in cases:
        result = runner.invoke(app, base + extra)
        assert result.exit_code == 2, (extra, result.output)
        assert message in result.output, (extra, result.output)
    bad = tmp_path / "bad.toml"
    bad.write_text("target = {jawOpen = 1}\n[ga]\nmutaton_genes = 3\n")
    result = runner.invoke(app, [*base, "--config", str(bad)])
    assert result.exit_code == 2 and "unknown key 'mutaton_genes' in [ga]" in result.output


# ---- the faces table, other metrics, the CLI's new options --------------------------------------
from emogen.config import MetricConfig  # noqa: E402
from emogen.simulate.runner import FACE_COLUMNS  # noqa: E402


def test_faces_table_and_all_weights(ict_model, tmp_path: Path) -> None:
    cfg = SimulationConfig(target={"jawOpen": 0.8}, runs=3, seed=2)
    result = run_simulation(cfg, ict_model.rig, all_weights=True)
    faces = result.faces
    assert faces is not None and len(faces) == 3 * 11 * 10
    assert tuple(faces.columns[: len(FACE_COLUMNS)]) == FACE_COLUMNS
    # the weight columns are named as in study exports: w_<shape>
    assert list(faces.columns[len(FACE_COLUMNS) :]) == [f"w_{s}" for s in ict_model.rig.shape_names]
    # a face not selected has rank NA (never -1)
    assert faces["rank"].isna().any() and not (faces["rank"] < 0).any()
    # one elite per run and generation, and it is the table's elite
    elites = faces[faces["rank"] == 0].reset_index(drop=True)
    assert len(elites) == 33
    np.testing.assert_array_equal(elites["error"], result.table["elite_error"])
    # the selections follow the paper's schedule, elites first
    counts = faces[faces["rank"] >= 0].groupby(["run", "generation"]).size().to_numpy()
    assert counts[:11].tolist() == [2, 4, 4, 4, 4, 4, 5, 5, 5, 5, 1]
    assert set(faces.loc[faces["generation"] == 0, "operator"]) <= {
        "init_happy",
        "init_sad",
        "init_angry",
        "init_fearful",
        "init_arbitrary",
        "init_neutral",
    }
    assert (
        faces.loc[(faces["generation"] > 0) & (faces["slot"] == 0), "operator"] == "elite"
    ).all()
    # the faces table is a face table: an evolved face as the next target
    paths = write_simulation(result, tmp_path)
    assert [p.name for p in paths][-2:] == ["faces.parquet", "faces.csv"]
    last = faces[(faces["generation"] == 10) & (faces["rank"] == 0)].index[0]
    nxt = SimulationConfig(target_file=tmp_path / "faces.parquet", target_row=int(last), runs=2)
    record = run_simulation(nxt, ict_model.rig).record
    assert record["target_source"]["row"] == last
    weights = faces.loc[last, [f"w_{s}" for s in ict_model.rig.shape_names]].to_numpy(float)
    assert record["target_weights"] == {
        s: w for s, w in zip(ict_model.rig.shape_names, weights, strict=True) if w != 0
    }


def test_empirical_metrics_train_on_a_faces_table(ict_model, tmp_path: Path) -> None:
    train = run_simulation(
        SimulationConfig(target={"mouthSmile": 0.7}, runs=20, seed=1),
        ict_model.rig,
        all_weights=True,
    )
    write_simulation(train, tmp_path, csv=False)
    for name in ("pca_ed", "std_ed", "mahalanobis"):
        metric = MetricConfig(name=name, training=tmp_path / "faces.parquet", query="rank >= 0")
        cfg = SimulationConfig(target={"jawOpen": 1.0}, runs=4, seed=3, metric=metric)
        result = run_simulation(cfg, ict_model)
        details = result.record["metric_details"]
        assert details["n_train"] == int((train.faces["rank"] >= 0).sum())
        assert result.table["elite_distance"].ge(0).all()
        assert (result.table["elite_error"] <= 1).all()


def test_cli_simulate_metric_noise_weights_and_target_file(ict_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "a"
    base = ["simulate", "--model", str(ict_dir), "--runs", "3", "--seed", "4", "--no-progress"]
    args = [*base, "--target", "jawOpen=0.9", "--metric", "ed", "--noise-temperature", "0.1"]
    result = runner.invoke(app, [*args, "--all-weights", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "metric ed" in result.output
    record = json.loads((out / "simulation.json").read_text())
    assert record["config"]["metric"]["name"] == "ed"
    assert record["config"]["noise_temperature"] == 0.1
    faces = pd.read_parquet(out / "faces.parquet")
    assert "w_jawOpen" in faces.columns and len(faces) == 3 * 11 * 10
    result = runner.invoke(
        app,
        [
            *base,
            "--target-file",
            str(out / "faces.parquet"),
            "--target-row",
            "5",
            "--out",
            str(tmp_path / "b"),
        ],
    )
    assert result.exit_code == 0, result.output
    record = json.loads((tmp_path / "b" / "simulation.json").read_text())
    assert record["config"]["target_row"] == 5 and record["config"]["target"] is None
    corrected = [*base[:3], *base[5:], "--runs", "1", "--generations", "1", "--target", "jawOpen=1"]
    result = runner.invoke(
        app, [*corrected, "--correct", "--all-weights", "--out", str(tmp_path / "c")]
    )
    assert result.exit_code == 0, result.output
    record = json.loads((tmp_path / "c" / "simulation.json").read_text())
    assert record["corrected"] and record["config"]["correct"]
    faces = pd.read_parquet(tmp_path / "c" / "faces.parquet")
    assert "w_collision_lip_outer_left" in faces.columns  # the correctives' weights are shown
    result = runner.invoke(
        app, [*base, "--target", "jawOpen=1", "--metric", "std_ed", "--out", str(tmp_path / "d")]
    )
    assert result.exit_code == 2 and "metric 'std_ed' is empirical" in result.output
