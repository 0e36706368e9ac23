"""``emogen simulate`` and ``emogen sweep``: simulated studies, one configuration or a grid."""

from __future__ import annotations

import sys
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from emogen.cli.options import (
    JsonOpt,
    ModelOpt,
    RigOpt,
    at_least,
    friendly_errors,
    parse_named_weights,
    show_result,
)
from emogen.cli.outputs import ForceOpt, check_out_folder, moved, output_folder
from emogen.cli.simulate_dynamic import DynamicOpt, HoldTimingOpt, TargetTimingOpt

if TYPE_CHECKING:
    from emogen.simulate.runner import SimulationResult

__all__ = ["parse_range", "simulate_command", "sweep_command"]


class InitKind(StrEnum):
    protocol = "protocol"
    fixed = "fixed"


class Variant(StrEnum):
    emogen = "emogen"
    classical = "classical"


def parse_range(text: str, option: str = "--init-range") -> list[int]:
    """``"3-8"`` → ``[3, 8]`` with an error naming the option."""
    from emogen.errors import ConfigError

    lo, sep, hi = text.partition("-")
    try:
        return [int(lo), int(hi if sep else lo)]
    except ValueError:
        raise ConfigError(f"{option} must look like LO-HI (e.g. 3-8); got {text!r}") from None


class MetricChoice(StrEnum):
    cd = "cd"
    ed = "ed"
    vertex_rms = "vertex_rms"
    pca_ed = "pca_ed"
    std_ed = "std_ed"
    mahalanobis = "mahalanobis"


DaskOpt = Annotated[
    str | None,
    typer.Option(
        "--dask",
        help="Run on Dask: a scheduler address (tcp://host:8786) or 'local' (a LocalCluster).",
    ),
]
WorkersOpt = Annotated[
    int | None,
    typer.Option(
        "--workers",
        callback=at_least(1),
        help="Local worker processes (or LocalCluster workers with --dask local).",
    ),
]
ProgressOpt = Annotated[
    bool | None,
    typer.Option(
        "--progress/--no-progress", help="Progress bar (default: when stderr is a terminal)."
    ),
]
AllWeightsOpt = Annotated[
    bool,
    typer.Option("--all-weights", help="Write every shown face's full weights in faces.parquet."),
]
OutOpt = Annotated[Path, typer.Option("--out", "-o", help="Output folder.")]
TargetOpt = Annotated[
    list[str] | None,
    typer.Option("--target", "-t", help="Target NAME=VALUE (gene or shape); repeatable."),
]
TargetFileOpt = Annotated[
    Path | None,
    typer.Option("--target-file", help="Target from a face table (Parquet/CSV, shape columns)."),
]
TargetRowOpt = Annotated[
    int | None,
    typer.Option(
        "--target-row",
        callback=at_least(0),
        help="Row of --target-file (0 = the first row after the header).",
    ),
]
RunsOpt = Annotated[
    int | None, typer.Option("--runs", callback=at_least(1), help="Runs (default 500).")
]
SeedOpt = Annotated[int | None, typer.Option("--seed", help="Seed (default: fresh, recorded).")]
InitOpt = Annotated[
    InitKind | None, typer.Option("--init", help="Initialisation (default protocol).")
]
InitRangeOpt = Annotated[
    str | None,
    typer.Option("--init-range", help="Active genes per protocol face, LO-HI (default 3-8)."),
]
GenerationsOpt = Annotated[
    int | None, typer.Option("--generations", callback=at_least(1), help="G (default 10).")
]
VariantOpt = Annotated[
    Variant | None, typer.Option("--variant", help="emogen (default) or classical.")
]
EyeMotionOpt = Annotated[
    bool | None, typer.Option("--eye-motion/--no-eye-motion", help="Evolve eye shapes.")
]
MetricOpt = Annotated[
    MetricChoice | None,
    typer.Option("--metric", help="The observer's similarity metric (default cd)."),
]
TrainingOpt = Annotated[
    Path | None,
    typer.Option("--training", help="Training faces for pca_ed, std_ed, mahalanobis."),
]
NoiseOpt = Annotated[
    float | None,
    typer.Option("--noise-temperature", help="Softmax choice noise T (default 0: none)."),
]
CorrectOpt = Annotated[
    bool | None,
    typer.Option("--correct/--no-correct", help="Apply the model's corrections to shown faces."),
]
ConfigOpt = Annotated[
    Path | None,
    typer.Option(
        "--config",
        help="Simulation TOML (tables ga, ga.init, metric; keys target, runs, seed, …).",
    ),
]


def _some(**values: Any) -> dict[str, Any]:
    """The options given on the command line (those not None)."""
    return {k: v for k, v in values.items() if v is not None}


def simulation_settings(
    data: dict[str, Any],
    *,
    ga: dict[str, Any],
    init: dict[str, Any],
    top: dict[str, Any],
    metric: dict[str, Any],
    target: list[str] | None,
    target_file: Path | None,
    target_row: int | None,
) -> dict[str, Any]:
    """The config TOML's table ``data`` with the command line's settings laid over it."""
    from emogen.config import merge

    if init:
        ga = {**ga, "init": init}
    overrides: dict[str, Any] = ({"ga": ga} if ga else {}) | top
    if isinstance(data.get("metric"), str):
        data["metric"] = {"name": data["metric"]}
    if metric:
        overrides["metric"] = metric
    data = merge(data, overrides)
    if target:
        data.pop("target_file", None)
        data.pop("target_row", None)
        data["target"] = parse_named_weights(target, "--target")
    if target_file is not None:
        data.pop("target", None)
        data["target_file"] = str(target_file)
    if target_row is not None:
        data["target_row"] = target_row
    return data


def _summary(
    result: SimulationResult, runs: int, metric: str, paths: list[Path]
) -> tuple[dict[str, Any], list[str]]:
    """The result as JSON and as text lines."""
    from emogen.simulate.runner import summary

    stats = summary(result.table)
    means, sds = stats["mean"].to_numpy(float), stats["std"].to_numpy(float)
    ends = sorted({0, len(means) - 1})
    data = {
        "runs": runs,
        "seed": result.record["seed"],
        "metric": metric,
        "compute_seconds": result.record["compute_seconds"],
        "elite_error": [
            {"generation": g, "mean": float(means[g]), "sd": float(sds[g])} for g in ends
        ],
        "wrote": [str(p) for p in paths],
    }
    lines = [
        f"{runs} runs, seed {result.record['seed']}, metric {metric}, "
        f"{result.record['compute_seconds']:.2f} s; elite CD error (mean ± sd):",
        *(f"  generation {g:>3}: {means[g]:.3f} ± {sds[g]:.3f}" for g in ends),
        "wrote " + ", ".join(str(p) for p in paths),
    ]
    return data, lines


@friendly_errors
def simulate_command(
    out: OutOpt,
    target: TargetOpt = None,
    target_file: TargetFileOpt = None,
    target_row: TargetRowOpt = None,
    runs: RunsOpt = None,
    seed: SeedOpt = None,
    init: InitOpt = None,
    init_range: InitRangeOpt = None,
    generations: GenerationsOpt = None,
    variant: VariantOpt = None,
    eye_motion: EyeMotionOpt = None,
    metric: MetricOpt = None,
    training: TrainingOpt = None,
    noise_temperature: NoiseOpt = None,
    correct: CorrectOpt = None,
    dynamic: DynamicOpt = None,
    target_timing: TargetTimingOpt = None,
    hold_timing: HoldTimingOpt = None,
    all_weights: AllWeightsOpt = False,
    dask: DaskOpt = None,
    workers: WorkersOpt = None,
    progress: ProgressOpt = None,
    config: ConfigOpt = None,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Simulate studies: an observer selects faces by a metric toward a target.

    Writes simulation.parquet and simulation.csv (one row per run and generation: run,
    generation, elite_error, elite_distance, n_selected, run_seed), faces.parquet and faces.csv
    (one row per shown face; weights w_<shape>) and simulation.json (resolved config, seeds,
    record; also in the Parquet files' metadata). Columns: docs/data.md. With --dynamic also
    convergence.csv and convergence.png: the run beside held timing and static (docs/ga.md).
    """
    from emogen.cli import simulate_dynamic as dyn
    from emogen.config import SimulationConfig, read_toml, validate_config
    from emogen.model import load_model
    from emogen.simulate.backends import make_backend

    data = simulation_settings(
        read_toml(config) if config else {},
        ga=_some(
            generations=generations,
            variant=variant.value if variant is not None else None,
            eye_motion=eye_motion,
        ),
        init=_some(
            kind=init.value if init is not None else None,
            activation_range=parse_range(init_range) if init_range is not None else None,
        ),
        top=_some(runs=runs, seed=seed, noise_temperature=noise_temperature, correct=correct),
        metric=_some(
            name=metric.value if metric is not None else None,
            training=str(training) if training is not None else None,
        ),
        target=target,
        target_file=target_file,
        target_row=target_row,
    )
    data = dyn.dynamic_settings(data, dynamic, target_timing, hold_timing)
    cfg = validate_config(SimulationConfig, data, str(config) if config else "(command line)")
    check_out_folder(out, force=force)  # before the work, not after it
    model = load_model(model_path, rig=rig)
    backend = make_backend(dask, workers or 1)
    progress = sys.stderr.isatty() if progress is None else progress
    try:
        result, table = dyn.simulate(
            cfg, model, backend, progress=progress, all_weights=all_weights
        )
    finally:
        backend.close()
    with output_folder(out, force=force) as tmp:
        paths = moved(dyn.write(result, table, tmp), tmp, out)
    data, lines = _summary(result, cfg.runs, cfg.metric.name, paths)
    show_result(as_json, *dyn.with_convergence(table, data, lines))


@friendly_errors
def sweep_command(
    sweep_file: Annotated[Path, typer.Argument(help="Sweep TOML: [targets], [grid], settings.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder (resumable).")],
    all_weights: AllWeightsOpt = False,
    dask: DaskOpt = None,
    workers: WorkersOpt = None,
    progress: ProgressOpt = None,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Run a grid of simulations (targets × metrics × init × schedules × GA variant).

    Each cell is written to OUT/cells/<cell>/ as it finishes; cells already there with the
    same config hash are skipped, so an interrupted sweep resumes. OUT/summary.csv has one
    row per cell (elite CD error at generation 0 and G).
    """
    from emogen.model import load_model
    from emogen.simulate.backends import make_backend
    from emogen.simulate.sweep import load_sweep, run_sweep

    spec = load_sweep(sweep_file)
    model = load_model(model_path, rig=rig)
    backend = make_backend(dask, workers or 1)
    try:
        result = run_sweep(
            spec,
            model,
            out,
            backend=backend,
            progress=sys.stderr.isatty() if progress is None else progress,
            all_weights=all_weights,
            model_name=model.name,
            model_hash=model.model_hash,
        )
    finally:
        backend.close()
    rows: list[Any] = list(result.summary.itertuples())
    data = {
        "cells": len(spec.cells),
        "ran": result.ran,
        "skipped": result.skipped,
        "final_error": [
            {"cell": r.cell, "mean": float(r.mu_final), "sd": float(r.sigma_final)} for r in rows
        ],
        "wrote": str(out / "summary.csv"),
    }
    lines = [
        f"{len(spec.cells)} cells: ran {len(result.ran)}, skipped {len(result.skipped)} "
        f"(already done); elite CD error at the last generation (mean ± sd):",
        *(f"  {r.cell:<48} {r.mu_final:.3f} ± {r.sigma_final:.3f}" for r in rows),
        f"wrote {out / 'summary.csv'}",
    ]
    show_result(as_json, data, lines)
