"""Simulated observers of dynamic faces, and `emogen simulate --dynamic`."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.cli import app
from emogen.config import SimulationConfig
from emogen.errors import ConfigError
from emogen.metrics import cosine_distance
from emogen.metrics.dynamic import timing_distance, trajectory_cd
from emogen.rng import spawn_seeds
from emogen.simulate.convergence import compare_dynamic, convergence_table, final_rows
from emogen.simulate.dynamic import latencies, trajectory
from emogen.simulate.runner import DYNAMIC_COLUMNS, build_problem, run_simulation
from emogen.simulate.vectorised import engine_run, simulate_runs
from tests.r_readers import undocumented

runner = CliRunner()
TARGET = {"jawOpen": 0.6, "mouthSmile": 0.8, "browInnerUp": 0.5}
TIMING = {
    "jawOpen": (0.1, 0.3, 0.4, 0.5, 0.5),
    "mouthSmile": (0.3, 0.5, 0.5, 0.2, 0.6),
    "browInnerUp": (0.0, 0.8, 0.2, 0.5, 0.3),
}
FIELDS = ("distance", "error", "rank", "operators", "weights", "peak_error", "timing_error")


def dynamic_config(**dynamic: object) -> dict[str, object]:
    return {"timing": TIMING, **dynamic}


@pytest.mark.parametrize(
    "options",
    [{}, {"noise_temperature": 0.05}, {"hold": True}],
    ids=["free", "noise", "held-timing"],
)
def test_vectorised_dynamic_runs_equal_engine_runs(ict_model, options) -> None:
    """The engine driven one run at a time, as a participant would, gives the same numbers."""
    hold = bool(options.pop("hold", False))
    cfg = SimulationConfig(
        target=TARGET, runs=4, seed=9, dynamic=dynamic_config(hold_timing=hold), **options
    )
    problem = build_problem(cfg, ict_model.rig, all_weights=True)
    seeds = spawn_seeds(9, 4)
    fast = simulate_runs(problem, np.arange(4), np.array(seeds))
    for r in range(4):
        ref = engine_run(problem, r, seeds[r])
        for f in FIELDS:
            np.testing.assert_array_equal(getattr(fast, f)[r], getattr(ref, f)[0], err_msg=f)


def test_every_face_is_measured_by_the_dynamic_metrics(ict_model) -> None:
    """The recorded distances are the metrics of emogen.metrics.dynamic applied to the target
    written from the config (its amplitudes per gene and its timing), face by face."""
    cfg = SimulationConfig(target=TARGET, runs=2, seed=4, dynamic=dynamic_config(samples=11))
    problem = build_problem(cfg, ict_model.rig)
    rig = ict_model.rig
    names = rig.gene_names()
    target = np.zeros((len(names), 6))
    for name, amp in TARGET.items():
        target[names.index(name)] = [amp, *TIMING[name]]
    np.testing.assert_array_equal(
        problem.dynamic.target[target[:, 0] > 0], target[target[:, 0] > 0]
    )
    run = engine_run(problem, 0, 77)
    engine_genes = _generation_zero_genes(cfg, rig, 77)
    e = rig.expansion_matrix()
    times = np.linspace(0, 1.25, 11)
    view = problem.dynamic
    total = trajectory_cd(
        trajectory(view.genome, engine_genes, e, times), trajectory(view.genome, target, e, times)
    )
    np.testing.assert_allclose(run.error[0, 0], total, atol=1e-12)
    peak = cosine_distance(engine_genes[..., 0] @ e, target[:, 0] @ e)
    np.testing.assert_allclose(run.peak_error[0, 0], peak, atol=1e-12)
    np.testing.assert_allclose(
        run.timing_error[0, 0],
        timing_distance(
            latencies(view.genome, engine_genes),
            engine_genes[..., 0],
            latencies(view.genome, target),
            target[:, 0],
        ),
        atol=1e-12,
    )


def _generation_zero_genes(cfg: SimulationConfig, rig, seed: int) -> np.ndarray:
    from emogen.ga.engine import Engine
    from emogen.simulate.dynamic import genome_of_config

    engine = Engine(cfg.ga, rig, seed, genome=genome_of_config(cfg.dynamic))
    return np.asarray(engine.ask().genes)


def test_a_target_moving_as_one_curve_with_held_timing_is_the_static_run(ict_model) -> None:
    """Every gene of the target on one time course, the timing held: the observer's metric is
    exactly the static CD of the peaks, so the run makes the static run's choices."""
    same = (0.2, 0.4, 0.3, 0.6, 0.5)
    cfg = SimulationConfig(
        target=TARGET,
        runs=12,
        seed=21,
        dynamic={"timing": dict.fromkeys(TARGET, same), "hold_timing": True},
    )
    held = run_simulation(cfg, ict_model.rig).table
    static = run_simulation(cfg.model_copy(update={"dynamic": None}), ict_model.rig).table
    np.testing.assert_allclose(held["elite_error"], static["elite_error"], atol=1e-9)
    np.testing.assert_allclose(held["elite_peak_error"], static["elite_error"], atol=1e-9)
    assert (held["elite_timing_error"] == 0).all()
    # a static simulation records its config as before dynamic faces: no 'dynamic' key
    static_record = run_simulation(
        cfg.model_copy(update={"dynamic": None, "runs": 1}), ict_model.rig
    )
    assert "dynamic" not in static_record.record["config"]
    assert "dynamic_target" not in static_record.record


def test_held_timing_converges_like_the_static_run(ict_model) -> None:
    """The paper's static result reproduced when timing is fixed: held timing's final peak
    error is within three standard errors (from the runs' own spread) of the static run's on
    the same target and seed, while free timing's is not (the test can tell them apart)."""
    runs = 120
    cfg = SimulationConfig(target=TARGET, runs=runs, seed=5, dynamic=dynamic_config())
    table = convergence_table(compare_dynamic(cfg, ict_model.rig))
    last = final_rows(table).set_index(["run_kind", "part"])
    held = last.loc[("held_timing", "elite_peak_error")]
    static = last.loc[("static", "elite_peak_error")]
    free = last.loc[("dynamic", "elite_peak_error")]
    tolerance = 3 * math.sqrt((held["sd"] ** 2 + static["sd"] ** 2) / runs)
    assert abs(held["mean"] - static["mean"]) < tolerance, (held, static, tolerance)
    assert free["mean"] - static["mean"] > tolerance, (free, static, tolerance)
    # every generation, not only the last
    peak = table[table["part"] == "elite_peak_error"].pivot(
        index="generation", columns="run_kind", values="mean"
    )
    assert (abs(peak["held_timing"] - peak["static"]) < tolerance).all(), peak
    # the timing part: none when held, and it shrinks when timing evolves
    timing = table[table["part"] == "elite_timing_error"].set_index(["run_kind", "generation"])
    assert (timing.loc["held_timing", "mean"] == 0).all()
    assert timing.loc[("dynamic", 10), "mean"] < timing.loc[("dynamic", 0), "mean"]


@pytest.mark.parametrize(
    ("dynamic", "options", "message"),
    [
        (
            {"timing": {"jawOpen": TIMING["jawOpen"]}},
            {},
            r"missing for \['browInnerUp', 'mouthSmile'\]",
        ),
        ({"timing": {**TIMING, "jawOpn": (0, 0, 0, 0, 0)}}, {}, r"\['jawOpn'\] are not genes"),
        (
            {"timing": {**TIMING, "noseSneer": (0, 0, 0, 0, 0)}},
            {},
            r"\['noseSneer'\] have weight 0",
        ),
        ({"timing": TIMING}, {"target": {**TARGET, "mouthSmile_L": 0.3}}, "both shapes of a pair"),
    ],
    ids=["missing", "unknown", "unused", "asymmetric"],
)
def test_a_dynamic_target_that_does_not_fit_is_named(ict_model, dynamic, options, message) -> None:
    cfg = SimulationConfig(**{"target": TARGET, "runs": 1, "seed": 1, **options}, dynamic=dynamic)
    with pytest.raises(ConfigError, match=message):
        build_problem(cfg, ict_model.rig)


def test_cli_simulate_dynamic(ict_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "dyn"
    args = ["simulate", "--model", str(ict_dir), "--out", str(out), "--dynamic"]
    args += ["--runs", "6", "--seed", "8", "--generations", "4", "--json"]
    for name, amp in TARGET.items():
        args += [
            "-t",
            f"{name}={amp}",
            "--target-timing",
            f"{name}=" + ",".join(map(str, TIMING[name])),
        ]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    assert data["seed"] == 8
    record = json.loads((out / "simulation.json").read_text())
    assert record["seed"] == 8 and record["config"]["dynamic"]["timing"]["jawOpen"] == list(
        TIMING["jawOpen"]
    )
    assert record["dynamic_target"]["genes"]["mouthSmile"]["peak"] == TIMING["mouthSmile"][2]
    table = pd.read_parquet(out / "simulation.parquet")
    assert set(DYNAMIC_COLUMNS) <= set(table.columns) and len(table) == 6 * 5
    convergence = pd.read_csv(out / "convergence.csv")
    faces = pd.read_parquet(out / "faces.parquet")
    assert not undocumented(list(table.columns), "simulate: simulation")
    assert not undocumented(list(faces.columns), "simulate: faces")
    assert not undocumented(list(convergence.columns), "simulate: convergence")
    assert set(convergence["run_kind"]) == {"dynamic", "held_timing", "static"}
    assert (out / "convergence.png").stat().st_size > 10_000
    # the printed numbers are the table's last generation
    last = final_rows(convergence)
    assert [r["mean"] for r in data["convergence"]] == pytest.approx(last["mean"].tolist())
    dynamic_rows = convergence[
        (convergence["run_kind"] == "dynamic") & (convergence["part"] == "elite_error")
    ]
    assert dynamic_rows["mean"].tolist() == pytest.approx(
        table.groupby("generation")["elite_error"].mean().tolist()
    )


def test_cli_simulate_dynamic_errors(ict_dir: Path, tmp_path: Path) -> None:
    base = ["simulate", "--model", str(ict_dir), "--out", str(tmp_path / "x"), "-t", "jawOpen=0.5"]
    cases = [
        (
            ["--target-timing", "jawOpen=0.1,0.2,0.3,0.4,0.5"],
            "--target-timing and --hold-timing need --dynamic",
        ),
        (
            ["--dynamic", "--target-timing", "jawOpen=0.1,0.2"],
            "NAME=ONSET,ACCELERATION,PEAK,DECELERATION,OFFSET",
        ),
        (["--dynamic", "--target-timing", "jawOpen=a,b,c,d,e"], "'a,b,c,d,e' are not five numbers"),
        (["--dynamic", "--target-timing", "jawOpen=0.1,0.2,1.3,0.4,0.5"], "jawOpen"),
        (["--dynamic"], r"missing for \['jawOpen'\]"),
        (
            ["--dynamic", "--target-timing", "jawOpen=0,0,0,0,0", "--metric", "ed"],
            "needs metric 'cd'",
        ),
        (["--static", "--hold-timing"], "are for --dynamic, not --static"),
    ]
    for extra, message in cases:
        result = runner.invoke(app, base + extra)
        assert result.exit_code == 2, (extra, result.output)
        assert _matches(message, result.output), (extra, result.output)
    assert not (tmp_path / "x").exists()


def _matches(pattern: str, text: str) -> bool:
    import re

    return re.search(pattern, " ".join(text.split())) is not None
