"""Example faces: the golden-image tests, the documentation pictures and the benchmarks use them.

python -m emogen.render.examples [MODEL] [OUT_FOLDER]     # rewrites docs/images/render_*.png
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from emogen.model.face import FaceModel

# (name, identity, weights by shape or gene name)
EXAMPLES: tuple[tuple[str, str, dict[str, float]], ...] = (
    ("neutral", "generic", {}),
    (
        "smile",
        "generic",
        {
            "jawOpen": 0.3,
            "mouthSmile": 1.0,
            "mouthUpperUp": 0.6,
            "mouthLowerDown": 0.6,
            "cheekSquint": 0.6,
        },
    ),
    (
        "open_mouth",
        "generic",
        {"jawOpen": 0.6, "mouthLowerDown": 1.0, "mouthUpperUp": 0.8, "mouthStretch": 0.3},
    ),
    ("male", "male", {}),
    ("female", "female", {}),
)


def example_weights(model: FaceModel, name: str) -> tuple[FaceModel, np.ndarray]:
    """(model with the example's identity, weights (1, n_shapes)) of example ``name``."""
    for n, identity, named in EXAMPLES:
        if n == name:
            m = model.with_identity(identity)
            return m, m.rig.weights_from_names(named)[None]
    raise KeyError(name)


Example = tuple[str, str, dict[str, float]]


def render_examples(
    model: FaceModel, size: int = 512, examples: tuple[Example, ...] = EXAMPLES
) -> dict[str, np.ndarray]:
    """Examples (name, identity preset, named weights) drawn as a participant sees them — the
    preset's shape and appearance, the face framing: name → (size, size, 3) uint8."""
    from emogen.appearance.identities import resolve_identity
    from emogen.render.renderer import Renderer

    out: dict[str, np.ndarray] = {}
    by_identity: dict[str, list[Example]] = {}
    for example in examples:
        by_identity.setdefault(example[1], []).append(example)
    for name, todo in by_identity.items():
        identity = resolve_identity(name)
        m = model.with_identity(identity.shape)
        w = np.stack([m.rig.weights_from_names(named) for _, _, named in todo])
        with Renderer(m, size=size, appearance=identity.appearance) as r:
            for (n, _, _), image in zip(todo, r.render(w), strict=True):
                out[n] = image
    return {e[0]: out[e[0]] for e in examples}


def write_doc_images(model: FaceModel, folder: str | Path) -> list[Path]:
    """docs/images: each example, a heatmap (jawOpen 1 vs 0.5) and a contact sheet."""
    from emogen.render.distance_map import render_heatmap
    from emogen.render.images import contact_sheet, save_png
    from emogen.render.renderer import Renderer

    folder = Path(folder)
    paths = []
    images = render_examples(model)
    for name, image in images.items():
        paths.append(save_png(folder / f"render_{name}.png", image))
    small = render_examples(model, size=256)
    sheet = contact_sheet(np.stack(list(small.values())), [n.replace("_", " ") for n in small])
    paths.append(save_png(folder / "render_sheet.png", sheet))
    w = np.stack([model.rig.weights_from_names({"jawOpen": x}) for x in (1.0, 0.5)])
    faces = model.evaluate(w)
    with Renderer(model) as r:
        heat = render_heatmap(r, faces[0], faces[1])
    paths.append(save_png(folder / "render_heatmap.png", heat.image))
    return paths


def main() -> None:  # pragma: no cover - a maintenance script
    from emogen.model import load_model

    model = load_model(sys.argv[1] if len(sys.argv) > 1 else None)
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/images"
    for p in write_doc_images(model, out):
        sys.stdout.write(f"wrote {p}\n")


if __name__ == "__main__":  # pragma: no cover
    main()
