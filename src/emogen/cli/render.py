"""`emogen render`: faces to PNG, contact sheets and error heatmaps.

emogen render --weight jawOpen=1 --out a.png
emogen render --weight jawOpen=1 --identity male-dark --framing head --out b.png
emogen render --weights faces.csv --out faces/          (one PNG per row)
emogen render sheet --weights faces.csv --out sheet.png
emogen render heatmap --weight jawOpen=1 --reference-weight jawOpen=0.5 --out heat.png
emogen render clip face_curves.csv --select face_id=3 --out clip.webp --sheet keys.png
"""

from __future__ import annotations

from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

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
from emogen.cli.outputs import ForceOpt, check_out_folder, output_folder
from emogen.cli.render_clip import clip
from emogen.cli.render_setup import (
    BackgroundOpt,
    CorrectOpt,
    FovOpt,
    Framing,
    FramingOpt,
    IdentityOpt,
    PlainOpt,
    SizeOpt,
    SupersampleOpt,
    WeightOpt,
    WeightsFileOpt,
    faces_from_options,
    image_metadata,
    load_render_model,
    look_record,
    make_renderer,
    output_paths,
    png_file,
    render_appearance,
)

if TYPE_CHECKING:
    import numpy as np

    from emogen.model.rig import Rig


PngOutOpt = Annotated[Path, typer.Option("--out", "-o", help="PNG file.")]

render_app = typer.Typer(
    help="Render faces to PNG (offscreen OpenGL): one face, a contact sheet, an error heatmap, "
    "a face that moves (an animation, its frames, a sheet of key frames).",
)
render_app.command("clip")(friendly_errors(clip))


@render_app.callback(invoke_without_command=True)
@friendly_errors
def render(
    ctx: typer.Context,
    out: Annotated[
        Path | None,
        typer.Option("--out", "-o", help="PNG file (one face), or a folder / {i} pattern."),
    ] = None,
    weight: WeightOpt = None,
    weights_file: WeightsFileOpt = None,
    identity: IdentityOpt = None,
    size: SizeOpt = None,
    background: BackgroundOpt = None,
    fov: FovOpt = None,
    supersample: SupersampleOpt = None,
    footer: Annotated[
        bool, typer.Option("--footer/--no-footer", help="Write the ICT-FaceKit notice on it.")
    ] = False,
    gaze: Annotated[
        bool, typer.Option("--gaze/--no-gaze", help="Turn the eyeballs with eyeLook* weights.")
    ] = True,
    correct: CorrectOpt = False,
    framing: FramingOpt = Framing.face,
    plain: PlainOpt = False,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    force: ForceOpt = False,
    as_json: JsonOpt = False,
) -> None:
    """Render faces offscreen to PNG (512×512, frontal camera, the viewer's look) with an
    identity's shape and appearance."""
    if ctx.invoked_subcommand is not None:
        return
    from emogen.errors import ConfigError
    from emogen.render.images import add_footer, save_png

    if out is None:
        raise ConfigError("--out is required (a .png file, or a folder for several faces)")
    model, name, ident = load_render_model(model_path, rig, identity)
    w, labels = faces_from_options(model, weight, weights_file)
    paths = output_paths(out, len(w), labels)
    folder = paths[0].parent == out and "{" not in str(out)  # face_NNN.png in a folder
    if folder:
        check_out_folder(out, force=force)
    appearance = render_appearance(model, ident, plain)
    look = look_record(name, ident, appearance, framing)
    with make_renderer(
        model, size, background, fov, supersample, appearance=appearance, framing=framing
    ) as r:
        images = list(r.render(w, gaze=gaze, correct=correct))
        if footer:
            images = [add_footer(im, background=r.look.background_srgb) for im in images]
    metas = [
        image_metadata(model, w[i], label=labels[i], corrected=correct, **look)
        for i in range(len(paths))
    ]
    with output_folder(out, force=force) if folder else nullcontext(None) as tmp:
        for path, image, meta in zip(paths, images, metas, strict=True):
            save_png(path if tmp is None else tmp / path.name, image, meta)
    show_result(
        as_json,
        {"wrote": [str(p) for p in paths], "labels": labels},
        [f"wrote {paths[0]}" if len(paths) == 1 else f"wrote {len(paths)} faces to {out}"],
    )


@render_app.command("sheet")
@friendly_errors
def sheet(
    out: PngOutOpt,
    weights_file: WeightsFileOpt = None,
    face: Annotated[
        list[str] | None,
        typer.Option(
            "--face", help="One face as NAME=VALUE[,NAME=VALUE…] ('neutral' for none); repeatable."
        ),
    ] = None,
    columns: Annotated[
        int, typer.Option("--columns", callback=at_least(1), help="Faces per row.")
    ] = 5,
    labels: Annotated[bool, typer.Option("--labels/--no-labels", help="Label each face.")] = True,
    identity: IdentityOpt = None,
    size: Annotated[
        int, typer.Option("--size", callback=at_least(1), help="Side of each face in pixels.")
    ] = 256,
    background: BackgroundOpt = None,
    fov: FovOpt = None,
    supersample: SupersampleOpt = None,
    correct: CorrectOpt = False,
    framing: FramingOpt = Framing.face,
    plain: PlainOpt = False,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """A contact sheet: faces in a grid with labels and the ICT-FaceKit notice."""
    import numpy as np

    from emogen.errors import ConfigError
    from emogen.render.images import save_png
    from emogen.render.weights import describe

    png_file(out)  # before any work
    model, name, ident = load_render_model(model_path, rig, identity)
    rows: list[np.ndarray] = []
    names: list[str] = []
    if weights_file is not None:
        w, names = faces_from_options(model, None, weights_file)
        rows.extend(w)
    for spec in face or []:
        items = [] if spec.strip().lower() in ("", "neutral") else spec.split(",")
        named = parse_named_weights(items, "--face")
        rows.append(model.rig.weights_from_names(named))
        names.append(describe(named))
    if not rows:
        raise ConfigError("give faces with --weights FILE.csv and/or --face NAME=VALUE,…")
    appearance = render_appearance(model, ident, plain)
    look = look_record(name, ident, appearance, framing)
    with make_renderer(
        model, size, background, fov, supersample, appearance=appearance, framing=framing
    ) as r:
        image = r.sheet(
            np.asarray(rows), names if labels else None, columns=columns, correct=correct
        )
    save_png(
        png_file(out), image, image_metadata(model, None, faces=names, corrected=correct, **look)
    )
    show_result(as_json, {"wrote": str(out), "faces": names}, [f"wrote {out}: {len(rows)} faces"])


def _heatmap_pair(
    rig: Rig, weight: list[str] | None, reference: list[str] | None, weights_file: Path | None
) -> np.ndarray:
    """The face and its reference, (2, shapes): from ``--weights`` or the named weights."""
    import numpy as np

    from emogen.errors import ConfigError
    from emogen.render.weights import read_weights_csv

    if weights_file is not None:
        if weight or reference:
            raise ConfigError("give either --weights FILE.csv or --weight/--reference-weight")
        w, _ = read_weights_csv(weights_file, rig)
        if len(w) != 2:
            raise ConfigError(
                f"--weights {weights_file}: a heatmap needs 2 rows (face, reference); got {len(w)}"
            )
        return w
    return np.stack(
        [
            rig.weights_from_names(parse_named_weights(weight)),
            rig.weights_from_names(parse_named_weights(reference, "--reference-weight")),
        ]
    )


@render_app.command("heatmap")
@friendly_errors
def heatmap(
    out: PngOutOpt,
    weight: WeightOpt = None,
    reference_weight: Annotated[
        list[str] | None,
        typer.Option(
            "--reference-weight", "-r", help="Reference face NAME=VALUE (default: neutral)."
        ),
    ] = None,
    weights_file: Annotated[
        Path | None,
        typer.Option("--weights", help="CSV with two rows: the face, then the reference."),
    ] = None,
    vmax: Annotated[
        float | None, typer.Option("--max-cm", help="Top of the colour scale, cm (default: auto).")
    ] = None,
    cmap: Annotated[
        str, typer.Option("--cmap", help="Perceptual colour map: viridis, cividis, magma, …")
    ] = "viridis",
    identity: IdentityOpt = None,
    size: SizeOpt = None,
    background: BackgroundOpt = None,
    fov: FovOpt = None,
    supersample: SupersampleOpt = None,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Per-vertex distance between two faces as colour on the face, legend in cm (paper Fig. 9)."""
    import numpy as np

    from emogen.render.distance_map import render_heatmap
    from emogen.render.images import save_png

    png_file(out)  # before any work
    # the heatmap colours the face: no skin
    model, name, _ = load_render_model(model_path, rig, identity)
    w = _heatmap_pair(model.rig, weight, reference_weight, weights_file)
    faces = model.evaluate(w.astype(np.float32))
    with make_renderer(model, size, background, fov, supersample) as r:
        result = render_heatmap(r, faces[0], faces[1], vmax=vmax, cmap=cmap)
    save_png(
        png_file(out),
        result.image,
        image_metadata(
            model,
            w[0],
            identity=name,
            reference={s: float(x) for s, x in zip(model.shape_names, w[1], strict=True) if x},
            vmax_cm=result.vmax,
            max_distance_cm=result.max_distance,
        ),
    )
    show_result(
        as_json,
        {
            "wrote": str(out),
            "max_distance_cm": float(result.max_distance),
            "scale_max_cm": float(result.vmax),
        },
        [f"wrote {out}: largest distance {result.max_distance:.3f} cm, scale 0-{result.vmax:g} cm"],
    )
