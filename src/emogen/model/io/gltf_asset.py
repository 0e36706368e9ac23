"""What every EmoGen GLB carries besides its mesh: asset metadata, licence, materials, gaze.

glTF is in metres; EmoGen models are in centimetres (ICT-FaceKit's unit), so exports scale by
:data:`CM_TO_M` and :func:`~emogen.model.io.gltf_import.import_glb` multiplies by 100.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.errors import ModelFileError, ResourceError
from emogen.model.geometry import sphere_fit
from emogen.model.io.glb import read_glb_json
from emogen.model.io.gltf_layout import ExportLayout, contained_regions

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

__all__ = [
    "CM_TO_M",
    "EXTRAS_FORMAT",
    "ICT_COPYRIGHT",
    "asset_header",
    "gaze_extras",
    "materials",
    "model_licence",
    "write_file",
]

ICT_COPYRIGHT = "ICT-FaceKit © 2020 USC Institute for Creative Technologies, MIT licence"
EXTRAS_FORMAT = 1
CM_TO_M = 0.01

# Plain PBR colours (sRGB) by material-name keyword, for viewers that show the GLB as is.
_COLOURS = (
    ("lash", (0.08, 0.06, 0.05)),
    ("iris", (0.32, 0.22, 0.14)),
    ("sclera", (0.93, 0.92, 0.89)),
    ("teeth", (0.92, 0.89, 0.80)),
    ("gum", (0.78, 0.40, 0.42)),
    ("tongue", (0.78, 0.40, 0.42)),
)
_SKIN = (0.82, 0.64, 0.55)


def model_licence(model: FaceModel) -> tuple[str | None, str | None]:
    """(copyright line, licence text) to carry with exports of ``model``."""
    src = Path(model.source) if model.source else None
    if src is not None and src.suffix.lower() in (".glb", ".gltf") and src.is_file():
        try:
            asset = read_glb_json(src).get("asset", {})
        except ModelFileError:
            asset = {}
        return asset.get("copyright"), (asset.get("extras") or {}).get("license")
    text = None
    for cand in (src.parent / "LICENSE", src / "LICENSE") if src is not None else ():
        if cand.is_file():
            text = cand.read_text(encoding="utf-8", errors="replace")
            break
    is_ict = model.name.startswith("ict-facekit") or (
        text is not None and "Institute for Creative Technologies" in text
    )
    return (ICT_COPYRIGHT if is_ict else None), text


def gaze_extras(model: FaceModel) -> dict[str, Any] | None:
    """What a viewer needs to turn the eyeballs (morph targets cannot): centres in metres."""
    gz = model.rig.gaze
    if gz is None or not {gz.left_eyeball, gz.right_eyeball} <= set(model.regions):
        return None
    centre = {
        side: [
            float(x) * CM_TO_M for x in sphere_fit(model.neutral[model.regions[name].vertices])[0]
        ]
        for side, name in (("left", gz.left_eyeball), ("right", gz.right_eyeball))
    }
    names = np.asarray(model.shape_names)
    return {
        "left_eyeball": gz.left_eyeball,
        "right_eyeball": gz.right_eyeball,
        "left_centre": centre["left"],
        "right_centre": centre["right"],
        **{
            k: names[getattr(gz, k)].tolist()
            for k in ("look_left", "look_right", "look_up", "look_down")
        },
        "yaw_deg": float(np.degrees(gz.yaw)),
        "pitch_up_deg": float(np.degrees(gz.pitch_up)),
        "pitch_down_deg": float(np.degrees(gz.pitch_down)),
        "rule": "yaw = yaw_deg * (mean(look_left) - mean(look_right)); pitch = pitch_up_deg * "
        "mean(look_up) - pitch_down_deg * mean(look_down); rotate each eyeball about its centre "
        "by yaw about +y then pitch about -x",
    }


def asset_header(model: FaceModel, layout: ExportLayout, extra: dict[str, Any]) -> dict[str, Any]:
    from emogen import __version__

    copyright_line, licence = model_licence(model)
    emogen_extras: dict[str, Any] = {
        "format": EXTRAS_FORMAT,
        "model_name": model.name,
        "model_hash": model.model_hash,
        "identity": model.identity_label,
        "units": "metres in the file; EmoGen models are in centimetres",
        "source_vertex_count": model.n_vertices,
        "source_polygon_count": len(model.polygons),
        "parts": list(layout.parts),
        "regions": contained_regions(model, layout),
        **extra,
    }
    asset: dict[str, Any] = {"version": "2.0", "generator": f"EmoGen {__version__}"}
    if copyright_line:
        asset["copyright"] = copyright_line
    asset["extras"] = {"emogen": emogen_extras, **({"license": licence} if licence else {})}
    return asset


def materials(model: FaceModel, layout: ExportLayout) -> list[dict[str, Any]]:
    out = []
    for prim in layout.primitives:
        name = (
            model.materials[prim.material]
            if prim.material < len(model.materials)
            else f"material_{prim.material}"
        )
        srgb = next((c for key, c in _COLOURS if key in name.lower()), _SKIN)
        linear = [float(((x + 0.055) / 1.055) ** 2.4) for x in srgb]
        out.append(
            {
                "name": name,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [*linear, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 0.6,
                },
                **({"doubleSided": True} if "lash" in name.lower() else {}),
            }
        )
    return out


def write_file(path: Path, data: bytes) -> None:
    try:
        Path(path).write_bytes(data)
    except OSError as exc:
        raise ResourceError(f"cannot write {path}: {exc.strerror}") from None
