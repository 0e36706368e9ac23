"""``emogen model info|export|fetch``: inspect the face model, export it, download it."""

from __future__ import annotations

import json
import sys
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from emogen.cli.options import (
    IdentityOpt,
    JsonOpt,
    ModelOpt,
    RigOpt,
    friendly_errors,
    parse_named_weights,
    show_result,
)

__all__ = ["model_app"]

model_app = typer.Typer(help="The face model: inspect, export, fetch.", no_args_is_help=True)


@model_app.command("info")
@friendly_errors
def model_info(
    path: Annotated[
        Path | None, typer.Argument(help="Model folder or GLB (the same as --model).")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
    rig: RigOpt = None,
    model_path: ModelOpt = None,
) -> None:
    """Shape names, genes, pairs, regions, vertex and face counts, and the model hash."""
    from emogen.errors import ConfigError
    from emogen.model import load_model

    if path is not None and model_path is not None and path != model_path:
        raise ConfigError(f"give the model once: PATH {path} or --model {model_path}")
    model = load_model(path if path is not None else model_path, rig=rig)
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
    as_json: JsonOpt = False,
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
        from emogen.render.model_glb import export_model_glb

        report = export_model_glb(model, out)
        show_result(as_json, {"wrote": str(out), "report": str(report)}, [f"wrote {out}: {report}"])
        return
    weights = model.rig.weights_from_names(named)
    if kind == "glb":
        gltf.export_face_glb(model, weights, out)
    else:
        gltf.export_face_obj(model, weights, out)
    show_result(as_json, {"wrote": str(out)}, [f"wrote {out}"])


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
    as_json: JsonOpt = False,
) -> None:
    """Download ICT-FaceKit (MIT) at the pinned commit, verify checksums, install it."""
    from emogen.model.io.fetch import fetch_model

    folder = fetch_model(dest, base_url=base_url, progress=not quiet and sys.stderr.isatty())
    notice = (
        "ICT-FaceKit © 2020 USC Institute for Creative Technologies, MIT licence (see LICENSE "
        "beside it)."
    )
    show_result(
        as_json,
        {"folder": str(folder), "notice": notice},
        [f"ICT-FaceKit installed in {folder}", notice],
    )
