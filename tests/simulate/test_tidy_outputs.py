"""Simulation, sweep and analysis outputs as R and pandas read them: exact run seeds, NA (not
−1) for faces not selected, weight columns named as in study exports, the record in every
Parquet file, machine-friendly analysis tables, and every column in docs/data.md."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
from typer.testing import CliRunner

from emogen import __version__
from emogen import columns as tidy
from emogen.analysis.data import load_dataset
from emogen.cli.analysis import analysis_app
from emogen.config import GAConfig, SimulationConfig
from emogen.simulate.runner import RECORD_SCHEMA, run_simulation, write_simulation
from emogen.simulate.sweep import Cell, Sweep, sweep_summary
from tests.r_readers import col_types_of, read_in_r, undocumented

CONFIG = SimulationConfig(target={"jawOpen": 0.9}, runs=4, seed=11, ga=GAConfig(generations=3))


def _simulate(rig, out: Path, target: dict[str, float] | None = None) -> dict:  # type: ignore[no-untyped-def]
    cfg = CONFIG if target is None else CONFIG.model_copy(update={"target": target})
    result = run_simulation(cfg, rig, all_weights=True, model_name="m", model_hash="abc123")
    write_simulation(result, out)
    return result.record


def test_simulation_outputs_keep_seeds_exact_and_carry_the_record(
    ict_model, tmp_path: Path, rscript: None
) -> None:  # type: ignore[no-untyped-def]
    record = _simulate(ict_model.rig, tmp_path)
    assert record["schema"] == RECORD_SCHEMA == "emogen.simulate/4"
    seeds = record["run_seeds"]
    assert any(s > 2**53 for s in seeds), "the test needs seeds a double cannot hold"
    # R reads the CSV: the seeds are text and exact
    in_r = read_in_r([tmp_path / "simulation.csv", tmp_path / "faces.csv"])
    table, csv_faces = (t.frame for t in in_r)
    assert in_r[0].classes["run_seed"] == "character"
    first = table.groupby("run")["run_seed"].first()
    assert [int(s.removeprefix("s")) for s in first] == seeds
    # Parquet: exact int64, and the record in the file's own metadata
    for name in ("simulation", "faces"):
        meta = tidy.provenance(tmp_path / f"{name}.parquet")
        assert meta["seed"] == 11 and meta["run_seeds"] == seeds
        assert meta["model"] == {"name": "m", "hash": "abc123"}
        assert meta["emogen_version"] == __version__ and "git_commit" in meta
        assert meta["config"]["target"] == {"jawOpen": 0.9}
    sim = pd.read_parquet(tmp_path / "simulation.parquet")
    assert pq.read_schema(tmp_path / "simulation.parquet").field("run_seed").type == "int64"
    assert sim.groupby("run")["run_seed"].first().tolist() == seeds
    pd.testing.assert_frame_equal(tidy.read_csv(tmp_path / "simulation.csv"), sim)
    # a face not selected has rank NA, in both files; never -1
    faces = pd.read_parquet(tmp_path / "faces.parquet")
    assert faces["rank"].isna().sum() == (faces["rank"].notna() == 0).sum() > 0
    assert in_r[1].classes["rank"] == "numeric"
    assert csv_faces["rank"].isna().sum() == faces["rank"].isna().sum()
    assert not (csv_faces["rank"] == -1).any()
    # weights are w_<shape>, as in a study export's faces table
    assert [c for c in faces.columns if c.startswith("w_")] == [
        f"w_{s}" for s in ict_model.rig.shape_names
    ]
    assert not undocumented(list(sim.columns), "simulate: simulation")
    assert not undocumented(list(faces.columns), "simulate: faces")


def test_old_simulation_outputs_still_analyse(ict_model, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """An ``emogen.simulate/3`` folder: bare shape names, rank −1 for not selected."""
    _simulate(ict_model.rig, tmp_path / "new")
    old = tmp_path / "old"
    old.mkdir()
    faces = pd.read_parquet(tmp_path / "new" / "faces.parquet")
    faces = faces.rename(columns=lambda c: c[2:] if c.startswith("w_") else c)
    faces["rank"] = faces["rank"].fillna(-1).astype("int64")
    faces.to_parquet(old / "faces.parquet", index=False)
    table = pd.read_parquet(tmp_path / "new" / "simulation.parquet").astype({"run_seed": "int64"})
    table.to_parquet(old / "simulation.parquet", index=False)
    record = json.loads((tmp_path / "new" / "simulation.json").read_text())
    (old / "simulation.json").write_text(json.dumps({**record, "schema": "emogen.simulate/3"}))
    a, b = load_dataset(tmp_path / "new"), load_dataset(old)
    assert a.columns == b.columns == tuple(ict_model.rig.shape_names)
    pd.testing.assert_frame_equal(
        a.elites.drop(columns="group"), b.elites.drop(columns="group"), check_dtype=False
    )


def test_sweep_summary_is_typed_and_documented(ict_model, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    labels = {
        "target": "t",
        "metric": "cd",
        "init": "protocol",
        "schedule": "paper",
        "variant": "emogen",
    }
    name = "__".join(labels.values())
    _simulate(ict_model.rig, tmp_path / "cells" / name)
    sweep = Sweep((Cell(name, labels, CONFIG),), "sweep.toml")
    summary = sweep_summary(sweep, tmp_path / "cells")
    assert not undocumented(list(summary.columns), "sweep: summary")


def test_analysis_tables_are_long_with_identifier_headers(
    ict_model, ict_dir: Path, tmp_path: Path, rscript: None
) -> None:  # type: ignore[no-untyped-def]
    for target in ("jawOpen", "mouthSmile"):
        _simulate(ict_model.rig, tmp_path / "sims" / target, {target: 0.9})
    args = [
        str(tmp_path / "sims"),
        "--out",
        str(tmp_path / "out"),
        "--model",
        str(ict_dir),
        "--no-render",
        "--noise-runs",
        "20",
    ]
    bad = CliRunner().invoke(analysis_app, ["analyse", *args, "--format", "jpeg"])
    assert bad.exit_code != 0 and "--format must be one or more of png, svg, pdf" in bad.output
    assert not (tmp_path / "out").exists()  # refused before any work
    result = CliRunner().invoke(analysis_app, ["analyse", *args, "--format", "pdf"])
    assert result.exit_code == 0, result.output
    figures = {p.name for p in (tmp_path / "out" / "figures").iterdir()}
    assert {"kl.png", "kl.pdf", "separability.png", "separability.pdf"} <= figures
    assert not any(f.endswith(".svg") for f in figures)
    assert (tmp_path / "out" / "index.html").is_file()
    tables = sorted((tmp_path / "out" / "tables").glob("*.csv"))
    names = {p.stem for p in tables}
    assert {"kl_by_generation", "repeatability", "confusion", "spread_test"} <= names
    groups = {"jawOpen", "mouthSmile"}
    types = col_types_of(tmp_path / "out" / "tables")  # readr's col_types of every table
    assert set(types) == names - {"col_types"}
    for path, in_r in zip(tables, read_in_r(tables, types), strict=True):
        df = in_r.frame
        assert in_r.problems == 0, path.name
        for c in df.columns:  # identifiers R and pandas take as they are
            assert re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", c), (path.name, c)
            assert c not in groups, (path.name, c)  # long format: groups are rows, not columns
            if df[c].dtype == object:  # one value per cell: no "0.2 ± 0.1", no "–"
                assert not df[c].dropna().str.contains("±|^–$").any(), (path.name, c)
        assert not undocumented(list(df.columns), f"analyse: {path.stem}"), path.name
    kl = pd.read_csv(tmp_path / "out" / "tables" / "kl_by_generation.csv")
    assert list(kl.columns) == ["group", "generation", "kl_nats"]
    assert set(kl["group"]) == groups and np.isfinite(kl["kl_nats"]).all()
    spread = pd.read_csv(tmp_path / "out" / "tables" / "spread_test.csv")
    assert spread["ga_noise_sd_to_target"].dtype == "float64"
    # the report itself still shows rounded, formatted values
    assert "±" in (tmp_path / "out" / "README.md").read_text()
