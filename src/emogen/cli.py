"""The `emogen` command line. Each command parses, loads what it needs, calls one library function."""

from __future__ import annotations

import json
import sys
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from emogen import __version__
from emogen.clitools import IdentityOpt, ModelOpt, RigOpt, friendly_errors, parse_named_weights

__all__ = ["IdentityOpt", "ModelOpt", "RigOpt", "app", "friendly_errors", "parse_named_weights"]

app = typer.Typer(
    name="emogen",
    help="EmoGen: evolve quantified 3D facial expressions with participants, and analyse them.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)
model_app = typer.Typer(help="The face model: inspect, export, fetch.", no_args_is_help=True)
app.add_typer(model_app, name="model")


def _version(value: bool) -> None:
    if value:
        typer.echo(f"emogen {__version__}")
        raise typer.Exit


@app.callback()
def main(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version.")
    ] = False,
) -> None:
    """EmoGen command line."""


@model_app.command("info")
@friendly_errors
def model_info(
    path: Annotated[
        Path | None, typer.Argument(help="Model folder or GLB (default: as --model).")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
    rig: RigOpt = None,
) -> None:
    """Shape names, genes, pairs, regions, vertex and face counts, and the model hash."""
    from emogen.model import load_model

    model = load_model(path, rig=rig)
    info = model.info()
    if as_json:
        typer.echo(json.dumps(info, indent=2))
        return
    rig_info: dict[str, Any] = info["rig"]  # type: ignore[assignment]
    typer.echo(f"model      {model.name}  ({model.source})")
    typer.echo(f"hash       {model.model_hash}")
    typer.echo(
        f"mesh       {model.n_vertices} vertices, {len(model.polygons)} polygons, "
        f"{len(model.faces)} triangles, {model.n_identity_modes} identity modes"
    )
    typer.echo(f"shapes     {model.n_shapes}: {', '.join(model.shape_names)}")
    genes = rig_info["genes"]
    typer.echo(f"genes      {len(genes)} ({len(model.rig.gene_names(False))} without eye motion)")
    for g in genes:
        typer.echo(f"  {g['name']:<16} {' + '.join(g['shapes'])}{'   [eye]' if g['eye'] else ''}")
    typer.echo("excluded")
    for shape, why in model.rig.excluded.items():
        typer.echo(f"  {shape:<16} {why}")
    typer.echo("emotions")
    for name, e in model.rig.emotions.items():
        typer.echo(
            f"  {name:<10} AU {e.action_units}: core {', '.join(e.core)}; optional {', '.join(e.optional)}"
        )
    from emogen.appearance.identities import PRESETS

    typer.echo(f"shapes     generic, {', '.join(sorted(model.rig.identities))}")
    typer.echo(f"identities {', '.join(PRESETS)} (shape + appearance)")
    typer.echo(f"regions    {', '.join(model.regions)}")


class ExportFormat(StrEnum):
    glb = "glb"
    obj = "obj"


@model_app.command("export")
@friendly_errors
def model_export(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output file (.glb or .obj).")],
    face: Annotated[
        bool,
        typer.Option("--face", help="Export one evaluated face (static mesh) instead of the rig."),
    ] = False,
    weight: Annotated[
        list[str] | None,
        typer.Option("--weight", "-w", help="NAME=VALUE (shape or gene); repeatable."),
    ] = None,
    fmt: Annotated[
        ExportFormat | None, typer.Option("--format", help="Default: from --out's suffix.")
    ] = None,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    identity: IdentityOpt = None,
) -> None:
    """Export the model as a GLB with morph targets (for the browser), or one face as GLB/OBJ."""
    from emogen.errors import ConfigError
    from emogen.model import load_model

    named = parse_named_weights(weight)
    kind = fmt.value if fmt else out.suffix.lower().lstrip(".")
    if kind not in ("glb", "obj"):
        raise ConfigError(
            f"--out {out}: cannot tell the format from suffix '{out.suffix}'; use --format glb|obj"
        )
    if named and not face:
        raise ConfigError(
            "--weight only makes sense with --face (the rig export carries every shape)"
        )
    from emogen.model.io import gltf

    model = load_model(model_path, identity, rig=rig)
    out.parent.mkdir(parents=True, exist_ok=True)
    if not face:
        if kind != "glb":
            raise ConfigError(
                "the rig (with morph targets) exports as GLB only; use --face for OBJ"
            )
        report = gltf.export_model_glb(model, out)
        typer.echo(f"wrote {out}: {report}")
        return
    weights = model.rig.weights_from_names(named)
    if kind == "glb":
        gltf.export_face_glb(model, weights, out)
    else:
        gltf.export_face_obj(model, weights, out)
    typer.echo(f"wrote {out}")


@model_app.command("fetch")
@friendly_errors
def model_fetch(
    dest: Annotated[
        Path | None, typer.Option("--dest", help="Install folder (default: the user cache).")
    ] = None,
    base_url: Annotated[
        str | None,
        typer.Option(
            "--base-url", help="Mirror URL or folder (default: $EMOGEN_MODEL_URL, then GitHub)."
        ),
    ] = None,
    quiet: Annotated[bool, typer.Option("--quiet", help="No progress bar.")] = False,
) -> None:
    """Download ICT-FaceKit (MIT) at the pinned commit, verify checksums, install it."""
    from emogen.model.io.fetch import fetch_model

    folder = fetch_model(dest, base_url=base_url, progress=not quiet and sys.stderr.isatty())
    typer.echo(f"ICT-FaceKit installed in {folder}")
    typer.echo(
        "ICT-FaceKit © 2020 USC Institute for Creative Technologies, MIT licence (see LICENSE beside it)."
    )


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
        "--workers", help="Local worker processes (or LocalCluster workers with --dask local)."
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


@app.command("simulate")
@friendly_errors
def simulate(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder.")],
    target: Annotated[
        list[str] | None,
        typer.Option("--target", "-t", help="Target NAME=VALUE (gene or shape); repeatable."),
    ] = None,
    target_file: Annotated[
        Path | None,
        typer.Option(
            "--target-file", help="Target from a face table (Parquet/CSV, shape columns)."
        ),
    ] = None,
    target_row: Annotated[
        int | None, typer.Option("--target-row", help="Row of --target-file (from 0).")
    ] = None,
    runs: Annotated[int | None, typer.Option("--runs", help="Runs (default 500).")] = None,
    seed: Annotated[
        int | None, typer.Option("--seed", help="Seed (default: fresh, recorded).")
    ] = None,
    init: Annotated[
        InitKind | None, typer.Option("--init", help="Initialisation (default protocol).")
    ] = None,
    init_range: Annotated[
        str | None,
        typer.Option("--init-range", help="Active genes per protocol face, LO-HI (default 3-8)."),
    ] = None,
    generations: Annotated[
        int | None, typer.Option("--generations", help="G (default 10).")
    ] = None,
    variant: Annotated[
        Variant | None, typer.Option("--variant", help="emogen (default) or classical.")
    ] = None,
    eye_motion: Annotated[
        bool | None, typer.Option("--eye-motion/--no-eye-motion", help="Evolve eye shapes.")
    ] = None,
    metric: Annotated[
        MetricChoice | None,
        typer.Option("--metric", help="The observer's similarity metric (default cd)."),
    ] = None,
    training: Annotated[
        Path | None,
        typer.Option("--training", help="Training faces for pca_ed, std_ed, mahalanobis."),
    ] = None,
    noise_temperature: Annotated[
        float | None,
        typer.Option("--noise-temperature", help="Softmax choice noise T (default 0: none)."),
    ] = None,
    correct: Annotated[
        bool | None,
        typer.Option(
            "--correct/--no-correct", help="Apply the model's corrections to shown faces."
        ),
    ] = None,
    all_weights: AllWeightsOpt = False,
    dask: DaskOpt = None,
    workers: WorkersOpt = None,
    progress: ProgressOpt = None,
    config: Annotated[
        Path | None,
        typer.Option(
            "--config",
            help="Simulation TOML (tables ga, ga.init, metric; keys target, runs, seed, …).",
        ),
    ] = None,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
) -> None:
    """Simulate studies: an observer selects faces by a metric toward a target.

    Writes simulation.parquet and simulation.csv (one row per run and generation: run,
    generation, elite_error, elite_distance, n_selected, run_seed), faces.parquet and faces.csv
    (one row per shown face) and simulation.json (resolved config, seeds, record).
    """
    from emogen.config import SimulationConfig, merge, read_toml, validate_config
    from emogen.model import load_model
    from emogen.simulate.backends import make_backend
    from emogen.simulate.runner import run_simulation, summary, write_simulation

    data: dict[str, Any] = read_toml(config) if config else {}
    ga: dict[str, Any] = {}
    init_opts: dict[str, Any] = {}
    if init is not None:
        init_opts["kind"] = init.value
    if init_range is not None:
        init_opts["activation_range"] = parse_range(init_range)
    if init_opts:
        ga["init"] = init_opts
    if generations is not None:
        ga["generations"] = generations
    if variant is not None:
        ga["variant"] = variant.value
    if eye_motion is not None:
        ga["eye_motion"] = eye_motion
    overrides: dict[str, Any] = {"ga": ga} if ga else {}
    if runs is not None:
        overrides["runs"] = runs
    if seed is not None:
        overrides["seed"] = seed
    if noise_temperature is not None:
        overrides["noise_temperature"] = noise_temperature
    if correct is not None:
        overrides["correct"] = correct
    metric_opts: dict[str, Any] = {}
    if isinstance(data.get("metric"), str):
        data["metric"] = {"name": data["metric"]}
    if metric is not None:
        metric_opts["name"] = metric.value
    if training is not None:
        metric_opts["training"] = str(training)
    if metric_opts:
        overrides["metric"] = metric_opts
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
    source = str(config) if config else "(command line)"
    cfg = validate_config(SimulationConfig, data, source)
    model = load_model(model_path, rig=rig)
    backend = make_backend(dask, workers or 1)
    try:
        result = run_simulation(
            cfg,
            model,
            model_name=model.name,
            model_hash=model.model_hash,
            backend=backend,
            progress=sys.stderr.isatty() if progress is None else progress,
            all_weights=all_weights,
        )
    finally:
        backend.close()
    paths = write_simulation(result, out)
    stats = summary(result.table)
    means, sds = stats["mean"].to_numpy(float), stats["std"].to_numpy(float)
    typer.echo(
        f"{cfg.runs} runs, seed {result.record['seed']}, metric {cfg.metric.name}, "
        f"{result.record['compute_seconds']:.2f} s; elite CD error (mean ± sd):"
    )
    for g in sorted({0, len(means) - 1}):
        typer.echo(f"  generation {g:>3}: {means[g]:.3f} ± {sds[g]:.3f}")
    typer.echo("wrote " + ", ".join(str(p) for p in paths))


@app.command("sweep")
@friendly_errors
def sweep(
    sweep_file: Annotated[Path, typer.Argument(help="Sweep TOML: [targets], [grid], settings.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder (resumable).")],
    all_weights: AllWeightsOpt = False,
    dask: DaskOpt = None,
    workers: WorkersOpt = None,
    progress: ProgressOpt = None,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
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
    typer.echo(
        f"{len(spec.cells)} cells: ran {len(result.ran)}, skipped {len(result.skipped)} "
        f"(already done); elite CD error at the last generation (mean ± sd):"
    )
    for row in result.summary.itertuples():
        typer.echo(f"  {row.cell:<48} {row.mu_final:.3f} ± {row.sigma_final:.3f}")
    typer.echo(f"wrote {out / 'summary.csv'}")


def _register_subcommands() -> None:
    """Command groups defined beside their packages (they import helpers from this module)."""
    from emogen.analysis.cli import analyse_command, power_command, replicate_command
    from emogen.correct.cli import correct_command
    from emogen.render.cli import render_app
    from emogen.study.cli import replay_command, serve_command, study_app

    app.add_typer(render_app, name="render")
    app.add_typer(study_app, name="study")
    app.command("serve")(serve_command)
    app.command("replay")(replay_command)
    app.command("correct")(correct_command)
    app.command("analyse")(analyse_command)
    app.command("replicate")(replicate_command)
    app.command("power")(power_command)


_register_subcommands()


if __name__ == "__main__":  # pragma: no cover
    app()
