"""`emogen render`: faces to PNG, contact sheets and error heatmaps.

emogen render --weight jawOpen=1 --out a.png
emogen render --weight jawOpen=1 --identity male-dark --framing head --out b.png
emogen render --weights faces.csv --out faces/          (one PNG per row)
emogen render sheet --weights faces.csv --out sheet.png
emogen render heatmap --weight jawOpen=1 --reference-weight jawOpen=0.5 --out heat.png
"""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from emogen.clitools import ModelOpt, RigOpt, friendly_errors, parse_named_weights

if TYPE_CHECKING:
    import numpy as np

    from emogen.appearance.identities import Identity
    from emogen.appearance.params import Appearance
    from emogen.model.face import FaceModel
    from emogen.render.renderer import Renderer

render_app = typer.Typer(
    help="Render faces to PNG (offscreen OpenGL): one face, a contact sheet, an error heatmap.",
)

WeightOpt = Annotated[
    list[str] | None,
    typer.Option("--weight", "-w", help="NAME=VALUE (shape or gene, 0-1); repeatable."),
]
WeightsFileOpt = Annotated[
    Path | None,
    typer.Option(
        "--weights",
        help="CSV: a header of shape/gene names (and optional 'label'), one face per row.",
    ),
]
SizeOpt = Annotated[int | None, typer.Option("--size", help="Image side in pixels (default 512).")]
BackgroundOpt = Annotated[
    str | None,
    typer.Option("--background", help="#rrggbb, R,G,B or white/black/grey (default grey)."),
]
FovOpt = Annotated[
    float | None, typer.Option("--fov", help="Vertical field of view, degrees (default 17.5).")
]
CorrectOpt = Annotated[
    bool,
    typer.Option("--correct/--no-correct", help="Apply the correctives (lip/teeth collisions)."),
]
SupersampleOpt = Annotated[
    int | None,
    typer.Option("--supersample", help="Anti-aliasing: render N× larger, average (default 2)."),
]
IdentityOpt = Annotated[
    str | None,
    typer.Option(
        "--identity",
        help="Identity: shape and appearance (skin tone, brows, lips, hair). Presets: "
        "female-light, female-medium, female-dark, male-light, male-medium, male-dark; "
        "generic, male, female (medium tone); or a shape preset of the rig. Default: generic.",
    ),
]


class Framing(StrEnum):
    face = "face"
    head = "head"


FramingOpt = Annotated[
    Framing,
    typer.Option(
        "--framing",
        help="face: hairline to chin fills the image; head: head and shoulders.",
    ),
]
PlainOpt = Annotated[
    bool,
    typer.Option(
        "--plain",
        help="Draw the earlier flat look (one colour per part: no skin tone, brows, lips or "
        "hair) instead of the identity's appearance.",
    ),
]


def _identity(model: FaceModel, name: str | None) -> tuple[str, Identity]:
    """(name, identity) of ``--identity``: a preset, else a shape preset of the model's rig."""
    from emogen.appearance.identities import PRESETS, Identity
    from emogen.errors import ConfigError

    name = name or "generic"
    if name in PRESETS:
        return name, PRESETS[name]
    if name in model.rig.identities:
        return name, Identity(shape=name)
    known = sorted({*PRESETS, *model.rig.identities})
    raise ConfigError(f"unknown identity '{name}'; known identities: {', '.join(known)}")


def _appearance(model: FaceModel, identity: Identity, plain: bool) -> Appearance | None:
    """The identity's appearance, or None (flat look) with --plain or a model without ICT's
    skin atlas (its regions and UVs), which is said on stderr."""
    from emogen.appearance.layout import SKIN_REGIONS

    if plain:
        return None
    if len(model.uvs) == 0 or any(r not in model.regions for r in SKIN_REGIONS):
        typer.echo(
            f"note: model '{model.name}' has no skin atlas (ICT-FaceKit's UV layout): "
            "drawing the plain look",
            err=True,
        )
        return None
    return identity.appearance


def _load(
    model_path: Path | None, rig: Path | None, identity: str | None
) -> tuple[FaceModel, str, Identity]:
    """The model with ``--identity``'s shape, the identity's name, and the identity."""
    from emogen.model import load_model

    base = load_model(model_path, rig=rig)
    name, ident = _identity(base, identity)
    return base.with_identity(ident.shape), name, ident


def _renderer(
    model: FaceModel,
    size: int | None,
    background: str | None,
    fov: float | None,
    supersample: int | None,
    *,
    appearance: Appearance | None = None,
    framing: Framing | None = None,
) -> Renderer:
    from emogen.render.look import parse_colour
    from emogen.render.renderer import Renderer

    return Renderer(
        model,
        size=size,
        background=parse_colour(background) if background else None,
        fov_y_deg=fov,
        supersample=supersample,
        appearance=appearance,
        framing=framing.value if framing is not None else None,
    )


def _faces(
    model: FaceModel, weight: list[str] | None, weights_file: Path | None
) -> tuple[np.ndarray, list[str]]:
    """Weights (n_faces, n_shapes) and labels from --weights rows, with --weight on top of each."""
    import numpy as np

    from emogen.render.weights import describe, read_weights_csv

    named = parse_named_weights(weight)
    extra = model.rig.weights_from_names(named)
    if weights_file is None:
        return extra[None], [describe(named)]
    w, labels = read_weights_csv(weights_file, model.rig)
    if named:
        mask = model.rig.weights_from_names(dict.fromkeys(named, 1.0)) > 0
        w = np.where(mask[None], extra[None], w)
    return w, labels


def _metadata(model: FaceModel, weights: np.ndarray | None = None, **extra: Any) -> dict[str, Any]:
    """PNG text chunks: software, copyright, and an ``emogen`` JSON record of the face (model,
    shape, identity and appearance when given in ``extra``, weights)."""
    from emogen import __version__
    from emogen.model.io.gltf import model_licence

    copyright_line, _ = model_licence(model)
    meta: dict[str, Any] = {"Software": f"EmoGen {__version__}"}
    if copyright_line:
        meta["Copyright"] = copyright_line
    record: dict[str, Any] = {
        "model": model.name,
        "model_hash": model.model_hash,
        "shape": model.identity_label,
        **extra,
    }
    if weights is not None:
        record["weights"] = {
            s: float(x) for s, x in zip(model.shape_names, weights, strict=True) if x != 0
        }
    meta["emogen"] = record
    return meta


def _look_record(
    name: str, identity: Identity, appearance: Appearance | None, framing: Framing | None
) -> dict[str, Any]:
    """What a stimulus's look depends on, for :func:`_metadata`: enough to render it again."""
    from emogen.appearance.params import GENERATOR_VERSION

    record: dict[str, Any] = {
        "identity": name,
        "appearance": None if appearance is None else appearance.record(),
        "appearance_generator": None if appearance is None else GENERATOR_VERSION,
    }
    shape = identity.shape
    if not isinstance(shape, str):
        record["shape_coefficients"] = list(shape)
    if framing is not None:
        record["framing"] = framing.value
    return record


def _output_paths(out: Path, n: int, labels: list[str]) -> list[Path]:
    if n == 1 and out.suffix.lower() == ".png":
        return [out]
    if "{" in str(out):
        return [Path(str(out).format(i=i, label=labels[i])) for i in range(n)]
    if out.suffix.lower() == ".png":
        from emogen.errors import ConfigError

        raise ConfigError(
            f"--out {out} names one PNG but there are {n} faces: give a folder, or a pattern "
            "with {i} (e.g. faces/face_{i:03d}.png)"
        )
    return [out / f"face_{i:03d}.png" for i in range(n)]


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
) -> None:
    """Render faces offscreen to PNG (512×512, frontal camera, the viewer's look) with an
    identity's shape and appearance."""
    if ctx.invoked_subcommand is not None:
        return
    from emogen.errors import ConfigError
    from emogen.render.images import add_footer, save_png

    if out is None:
        raise ConfigError("--out is required (a .png file, or a folder for several faces)")
    model, name, ident = _load(model_path, rig, identity)
    w, labels = _faces(model, weight, weights_file)
    paths = _output_paths(out, len(w), labels)
    appearance = _appearance(model, ident, plain)
    look = _look_record(name, ident, appearance, framing)
    with _renderer(
        model, size, background, fov, supersample, appearance=appearance, framing=framing
    ) as r:
        images = r.render(w, gaze=gaze, correct=correct)
        for i, path in enumerate(paths):
            image = (
                add_footer(images[i], background=r.look.background_srgb) if footer else images[i]
            )
            meta = _metadata(model, w[i], label=labels[i], corrected=correct, **look)
            save_png(path, image, meta)
    typer.echo(f"wrote {paths[0]}" if len(paths) == 1 else f"wrote {len(paths)} faces to {out}")


@render_app.command("sheet")
@friendly_errors
def sheet(
    out: Annotated[Path, typer.Option("--out", "-o", help="PNG file.")],
    weights_file: WeightsFileOpt = None,
    face: Annotated[
        list[str] | None,
        typer.Option(
            "--face", help="One face as NAME=VALUE[,NAME=VALUE…] ('neutral' for none); repeatable."
        ),
    ] = None,
    columns: Annotated[int, typer.Option("--columns", help="Faces per row.")] = 5,
    labels: Annotated[bool, typer.Option("--labels/--no-labels", help="Label each face.")] = True,
    identity: IdentityOpt = None,
    size: Annotated[int, typer.Option("--size", help="Side of each face in pixels.")] = 256,
    background: BackgroundOpt = None,
    fov: FovOpt = None,
    supersample: SupersampleOpt = None,
    correct: CorrectOpt = False,
    framing: FramingOpt = Framing.face,
    plain: PlainOpt = False,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
) -> None:
    """A contact sheet: faces in a grid with labels and the ICT-FaceKit notice."""
    import numpy as np

    from emogen.errors import ConfigError
    from emogen.render.images import save_png
    from emogen.render.weights import describe

    model, name, ident = _load(model_path, rig, identity)
    rows: list[np.ndarray] = []
    names: list[str] = []
    if weights_file is not None:
        w, names = _faces(model, None, weights_file)
        rows.extend(w)
    for spec in face or []:
        items = [] if spec.strip().lower() in ("", "neutral") else spec.split(",")
        named = parse_named_weights(items, "--face")
        rows.append(model.rig.weights_from_names(named))
        names.append(describe(named))
    if not rows:
        raise ConfigError("give faces with --weights FILE.csv and/or --face NAME=VALUE,…")
    appearance = _appearance(model, ident, plain)
    look = _look_record(name, ident, appearance, framing)
    with _renderer(
        model, size, background, fov, supersample, appearance=appearance, framing=framing
    ) as r:
        image = r.sheet(
            np.asarray(rows), names if labels else None, columns=columns, correct=correct
        )
    save_png(out, image, _metadata(model, None, faces=names, corrected=correct, **look))
    typer.echo(f"wrote {out}: {len(rows)} faces")


@render_app.command("heatmap")
@friendly_errors
def heatmap(
    out: Annotated[Path, typer.Option("--out", "-o", help="PNG file.")],
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
    cmap: Annotated[str, typer.Option("--cmap", help="matplotlib colour map.")] = "turbo",
    identity: IdentityOpt = None,
    size: SizeOpt = None,
    background: BackgroundOpt = None,
    fov: FovOpt = None,
    supersample: SupersampleOpt = None,
    model_path: ModelOpt = None,
    rig: RigOpt = None,
) -> None:
    """Per-vertex distance between two faces as colour on the face, legend in cm (paper Fig. 9)."""
    import numpy as np

    from emogen.errors import ConfigError
    from emogen.render.heatmap import render_heatmap
    from emogen.render.images import save_png
    from emogen.render.weights import read_weights_csv

    model, name, _ = _load(model_path, rig, identity)  # the heatmap colours the face: no skin
    if weights_file is not None:
        if weight or reference_weight:
            raise ConfigError("give either --weights FILE.csv or --weight/--reference-weight")
        w, _ = read_weights_csv(weights_file, model.rig)
        if len(w) != 2:
            raise ConfigError(
                f"--weights {weights_file}: a heatmap needs 2 rows (face, reference); got {len(w)}"
            )
    else:
        w = np.stack(
            [
                model.rig.weights_from_names(parse_named_weights(weight)),
                model.rig.weights_from_names(
                    parse_named_weights(reference_weight, "--reference-weight")
                ),
            ]
        )
    faces = model.evaluate(w.astype(np.float32))
    with _renderer(model, size, background, fov, supersample) as r:
        result = render_heatmap(r, faces[0], faces[1], vmax=vmax, cmap=cmap)
    save_png(
        out,
        result.image,
        _metadata(
            model,
            w[0],
            identity=name,
            reference={s: float(x) for s, x in zip(model.shape_names, w[1], strict=True) if x},
            vmax_cm=result.vmax,
            max_distance_cm=result.max_distance,
        ),
    )
    typer.echo(
        f"wrote {out}: largest distance {result.max_distance:.3f} cm, scale 0-{result.vmax:g} cm"
    )
