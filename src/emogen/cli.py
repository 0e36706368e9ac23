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


if __name__ == "__main__":  # pragma: no cover
    app()
