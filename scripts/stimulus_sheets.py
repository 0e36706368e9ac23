"""Before/after stimulus sheets for docs/images: the seven basic-expression prototypes (neutral
and the rig's six EMFACS core blocks at full weight) on the six identity presets.

    python scripts/stimulus_sheets.py [OUT_FOLDER]     # default docs/images
    python scripts/stimulus_sheets.py docs/images --rigs   # rig 1 and rig 2 (the reach shapes)
    python scripts/stimulus_sheets.py docs/images --dark   # the dark presets and their -v2
    python scripts/stimulus_sheets.py docs/images --v3     # the presets for new studies (-v3)
    python scripts/stimulus_sheets.py docs/images --rig3   # the same presets with rig 3
    python scripts/stimulus_sheets.py docs/images --long   # rig 3, the female ones long-haired

"before": the flat look of EmoGen ≤ 0.2 (no textures, head-and-shoulders framing);
"after": each preset's appearance and the face framing. 512² and the participant tile (256²).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image

import emogen
from emogen.appearance.identities import PRESETS
from emogen.render.images import contact_sheet
from emogen.render.renderer import Renderer

EMOTIONS = ("happy", "sad", "angry", "fearful", "surprised", "disgusted")
PRESET_NAMES = tuple(f"{s}-{t}" for s in ("female", "male") for t in ("light", "medium", "dark"))


def prototypes(model: emogen.FaceModel) -> tuple[list[str], np.ndarray]:
    names = ["neutral", *EMOTIONS]
    rows = [np.zeros(model.n_shapes)]
    for e in EMOTIONS:
        rows.append(model.rig.weights_from_names({g: 1.0 for g in model.rig.emotions[e].core}))
    return names, np.asarray(rows)


def packaged(rig: int) -> emogen.FaceModel:
    """The model with packaged rig ``rig`` (1 or 2; kept for replay), the sheets' "before"."""
    from importlib import resources

    file = resources.files("emogen.data").joinpath(f"ict_rig_{rig}.toml")
    with resources.as_file(file) as p:
        return emogen.load_model(rig=p)


def sheet(
    model: emogen.FaceModel,
    size: int,
    after: bool,
    framing: str = "face",
    presets: tuple[str, ...] = PRESET_NAMES,
) -> np.ndarray:
    names, w = prototypes(model)
    images, labels = [], []
    for preset in presets:
        ident = PRESETS[preset]
        m = model.with_identity(ident.shape)
        options = (
            {"appearance": ident.appearance, "framing": framing} if after else {"framing": "head"}
        )
        with Renderer(m, size=size, **options) as r:  # type: ignore[arg-type]
            images.append(r.render(w, correct=True))
        labels += [f"{preset} · {n}" for n in names]
    return contact_sheet(np.concatenate(images), labels, columns=len(names))


def textured_sheets(out: Path, tag: str) -> None:
    """The textured look under each framing, 512² and tile size: stimuli_TAG_FRAMING_SIZE.png
    (``--tag round1`` run with the previous release, ``round2`` with this one)."""
    model = emogen.load_model()
    for framing in ("face", "oval", "head"):
        for size, name in ((512, "512"), (256, "tile")):
            path = out / f"stimuli_{tag}_{framing}_{name}.png"
            Image.fromarray(sheet(model, size, True, framing)).save(path, optimize=True)
            print(path)


def rig_sheets(out: Path) -> None:
    """Rig 1 (before the reach shapes) and rig 2, textured, face framing, 512² and tile size:
    stimuli_rig1_face_SIZE.jpg and stimuli_rig2_face_SIZE.jpg."""
    models = {"rig1": packaged(1), "rig2": packaged(2)}
    for tag, model in models.items():
        for size, name in ((512, "512"), (256, "tile")):
            path = out / f"stimuli_{tag}_face_{name}.jpg"
            Image.fromarray(sheet(model, size, True)).save(path, quality=88, optimize=True)
            print(path)


def dark_sheets(out: Path) -> None:
    """The dark presets beside their -v2 (deeper lips), rig 2, face framing, 512² and tile size:
    stimuli_dark_v2_face_SIZE.jpg."""
    model = packaged(2)
    presets = ("female-dark", "female-dark-v2", "male-dark", "male-dark-v2")
    for size, name in ((512, "512"), (256, "tile")):
        path = out / f"stimuli_dark_v2_face_{name}.jpg"
        image = sheet(model, size, True, presets=presets)
        Image.fromarray(image).save(path, quality=88, optimize=True)
        print(path)


def v3_sheets(out: Path) -> None:
    """The six presets for new studies (light, medium, dark-v3: deeper wrinkles) and the dark
    presets' -v2 beside their -v3, rig 2, face framing, 512² and tile size:
    stimuli_v3_face_SIZE.jpg and stimuli_dark_v3_face_SIZE.jpg."""
    model = packaged(2)
    new = tuple(f"{s}-{t}" for s in ("female", "male") for t in ("light", "medium", "dark-v3"))
    dark = ("female-dark-v2", "female-dark-v3", "male-dark-v2", "male-dark-v3")
    for tag, presets in (("v3", new), ("dark_v3", dark)):
        for size, name in ((512, "512"), (256, "tile")):
            path = out / f"stimuli_{tag}_face_{name}.jpg"
            image = sheet(model, size, True, presets=presets)
            Image.fromarray(image).save(path, quality=88, optimize=True)
            print(path)


def rig3_sheets(out: Path) -> None:
    """The six presets for new studies with rig 3 (open smile, AU23, fear's parted lips), face
    framing, 512² and tile size: stimuli_rig3_face_SIZE.jpg; the "before" is the --v3 sheet
    (the same presets with rig 2)."""
    model = emogen.load_model()
    new = tuple(f"{s}-{t}" for s in ("female", "male") for t in ("light", "medium", "dark-v3"))
    for size, name in ((512, "512"), (256, "tile")):
        path = out / f"stimuli_rig3_face_{name}.jpg"
        image = sheet(model, size, True, presets=new)
        Image.fromarray(image).save(path, quality=88, optimize=True)
        print(path)


def long_hair_sheets(out: Path) -> None:
    """The six presets for new studies with rig 3, the female ones framed by long hair
    (``female-*-long``), face framing, 512² and tile size: stimuli_long_face_SIZE.jpg; the
    "before" is the --rig3 sheet (the same faces with the painted crop)."""
    model = emogen.load_model()
    new = (
        *(f"female-{t}-long" for t in ("light", "medium", "dark-v3")),
        *(f"male-{t}" for t in ("light", "medium", "dark-v3")),
    )
    for size, name in ((512, "512"), (256, "tile")):
        path = out / f"stimuli_long_face_{name}.jpg"
        image = sheet(model, size, True, presets=new)
        Image.fromarray(image).save(path, quality=88, optimize=True)
        print(path)


def main() -> None:
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/images")
    if "--rigs" in sys.argv:
        rig_sheets(out)
        return
    if "--dark" in sys.argv:
        dark_sheets(out)
        return
    if "--long" in sys.argv:
        long_hair_sheets(out)
        return
    if "--rig3" in sys.argv:
        rig3_sheets(out)
        return
    if "--v3" in sys.argv:
        v3_sheets(out)
        return
    if "--tag" in sys.argv:
        textured_sheets(out, sys.argv[sys.argv.index("--tag") + 1])
        return
    model = emogen.load_model()
    for after in (False, True):
        for size, tag in ((512, "512"), (256, "tile")):
            image = sheet(model, size, after)
            name = f"stimuli_{'after' if after else 'before'}_{tag}.jpg"
            Image.fromarray(image).save(out / name, quality=90, optimize=True)
            print(out / name, image.shape)


if __name__ == "__main__":
    main()
