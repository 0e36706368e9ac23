"""What the ``emogen render`` commands share: option types, the model, identity and renderer
they set up from those options, and the metadata written into every PNG."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from emogen.cli.options import at_least, parse_named_weights

if TYPE_CHECKING:
    import numpy as np

    from emogen.appearance.identities import Identity
    from emogen.appearance.params import Appearance
    from emogen.model.face import FaceModel
    from emogen.render.renderer import Renderer


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
SizeOpt = Annotated[
    int | None,
    typer.Option("--size", callback=at_least(1), help="Image side in pixels (default 512)."),
]
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
    typer.Option(
        "--supersample",
        callback=at_least(1),
        help="Anti-aliasing: render N× larger, average (default 2).",
    ),
]
IdentityOpt = Annotated[
    str | None,
    typer.Option(
        "--identity",
        help="Identity: shape and appearance (skin tone, brows, lips, hair). Presets: "
        "female-light, female-medium, female-dark-v3, male-light, male-medium, male-dark-v3 "
        "(female-light-long, …: the female ones framed by long hair under face framing) "
        "(female-dark, male-dark, …-v2: the older dark looks, paler lips, fainter wrinkles); "
        "generic, male, female (medium tone); or a shape preset of the rig. Default: generic.",
    ),
]


class Framing(StrEnum):
    face = "face"
    oval = "oval"
    head = "head"


FramingOpt = Annotated[
    Framing,
    typer.Option(
        "--framing",
        help="face: hairline to chin fills the image; oval: the face through an oval (hair, ears and neck hidden); head: head and shoulders.",
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


def resolve_render_identity(model: FaceModel, name: str | None) -> tuple[str, Identity]:
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


def render_appearance(model: FaceModel, identity: Identity, plain: bool) -> Appearance | None:
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


def load_render_model(
    model_path: Path | None, rig: Path | None, identity: str | None
) -> tuple[FaceModel, str, Identity]:
    """The model with ``--identity``'s shape, the identity's name, and the identity."""
    from emogen.model import load_model

    base = load_model(model_path, rig=rig)
    name, ident = resolve_render_identity(base, identity)
    return base.with_identity(ident.shape), name, ident


def make_renderer(
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


def faces_from_options(
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


def image_metadata(
    model: FaceModel, weights: np.ndarray | None = None, **extra: Any
) -> dict[str, Any]:
    """PNG text chunks: software, copyright, and an ``emogen`` JSON record of the face (model,
    shape, identity and appearance when given in ``extra``, weights)."""
    from emogen import __version__
    from emogen.model.io.gltf_asset import model_licence

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


def look_record(
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


def png_file(out: Path, option: str = "--out") -> Path:
    """``out`` when it names a .png file; any other file suffix (``a.jpg``) is an error."""
    from emogen.errors import ConfigError

    if out.suffix.lower() != ".png":
        raise ConfigError(
            f"{option} {out}: EmoGen writes PNG images (lossless, with the face's weights and "
            "model in their metadata); give a .png file name"
        )
    if out.is_dir():
        raise ConfigError(f"{option} {out} is a folder; give a .png file name")
    return out


def output_paths(out: Path, n: int, labels: list[str]) -> list[Path]:
    """Where the faces go: one .png, a ``{i}``/``{label}`` pattern, or face_NNN.png in a folder
    (a name with another image suffix, like ``a.jpg``, is refused: it is not a folder)."""
    from emogen.errors import ConfigError

    if out.suffix.lower() in (".jpg", ".jpeg", ".webp", ".tif", ".tiff", ".bmp", ".gif"):
        png_file(out)  # raises, naming it
    if n == 1 and out.suffix.lower() == ".png":
        return [png_file(out)]
    if "{" in str(out):
        return [Path(str(out).format(i=i, label=labels[i])) for i in range(n)]
    if out.suffix.lower() == ".png":
        raise ConfigError(
            f"--out {out} names one PNG but there are {n} faces: give a folder, or a pattern "
            "with {i} (e.g. faces/face_{i:03d}.png)"
        )
    return [out / f"face_{i:03d}.png" for i in range(n)]
