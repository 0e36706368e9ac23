"""The `emogen` command line. Each command parses, loads what it needs, calls one library function."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from enum import StrEnum
from functools import wraps
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer

from emogen import __version__
from emogen.errors import EmoGenError

app = typer.Typer(
    name="emogen",
    help="EmoGen: evolve quantified 3D facial expressions with participants, and analyse them.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)
model_app = typer.Typer(help="The face model: inspect, export, fetch.", no_args_is_help=True)
app.add_typer(model_app, name="model")

F = TypeVar("F", bound=Callable[..., Any])

ModelOpt = Annotated[
    Path | None,
    typer.Option(
        "--model",
        help="ICT-FaceKit FaceXModel folder or GLB (default: $EMOGEN_MODEL, then the user cache).",
    ),
]
RigOpt = Annotated[
    Path | None, typer.Option("--rig", help="Rig TOML (default: the packaged ICT rig).")
]
IdentityOpt = Annotated[
    str | None, typer.Option("--identity", help="Identity preset (generic, male, female).")
]


def _fail(message: str, code: int = 2) -> None:
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code)


def friendly_errors(func: F) -> F:
    """Turn EmoGen's errors into one red line and exit status 2, with no traceback."""

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except EmoGenError as exc:
            _fail(str(exc))

    return wrapper  # type: ignore[return-value]


def parse_named_weights(items: list[str] | None, option: str = "--weight") -> dict[str, float]:
    """``["jawOpen=0.8", ...]`` → ``{"jawOpen": 0.8}`` with errors that name the bad item."""
    from emogen.errors import ConfigError

    out: dict[str, float] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ConfigError(f"{option} must look like NAME=VALUE; got {item!r}")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise ConfigError(f"{option} {item!r}: value {value!r} is not a number") from None
    return out


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
    typer.echo(f"identities generic, {', '.join(sorted(model.rig.identities))}")
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


@app.command("simulate")
@friendly_errors
def simulate(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder.")],
    target: Annotated[
        list[str] | None,
        typer.Option("--target", "-t", help="Target NAME=VALUE (gene or shape); repeatable."),
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
    config: Annotated[
        Path | None,
        typer.Option("--config", help="Simulation TOML ([ga], [ga.init], target, runs, …)."),
    ] = None,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
) -> None:
    """Simulate studies: a cosine-distance observer evolves faces towards a target.

    Writes simulation.parquet and simulation.csv (one row per run and generation: run,
    generation, elite_error, n_selected, run_seed) and simulation.json (resolved config, seed).
    """
    from emogen.config import SimulationConfig, merge, read_toml, validate_config
    from emogen.model import load_model
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
    data = merge(data, overrides)
    if target:
        data["target"] = parse_named_weights(target, "--target")
    source = str(config) if config else "(command line)"
    cfg = validate_config(SimulationConfig, data, source)
    model = load_model(model_path, rig=rig)
    result = run_simulation(cfg, model.rig, model_name=model.name, model_hash=model.model_hash)
    paths = write_simulation(result, out)
    stats = summary(result.table)
    means, sds = stats["mean"].to_numpy(float), stats["std"].to_numpy(float)
    typer.echo(f"{cfg.runs} runs, seed {result.record['seed']}; elite CD error (mean ± sd):")
    for g in sorted({0, len(means) - 1}):
        typer.echo(f"  generation {g:>3}: {means[g]:.3f} ± {sds[g]:.3f}")
    typer.echo("wrote " + ", ".join(str(p) for p in paths))


if __name__ == "__main__":  # pragma: no cover
    app()
