"""Visibility of anger's glabellar furrows per identity preset, at 512² and tile size (256²).

Each preset's neutral and angry prototype (the rig's ``angry`` core block at weight 1, with the
correctives) is rendered as participants see it (``face`` framing). The **glabella** is sampled
in a disk (radius 0.55 cm, projected) centred 0.35 cm above the midpoint of the inner brow
ends (ICT landmarks 21 and 22) of the *angry* face, where the vertical furrows and the bulge of
AU4 lie. The figure is the Weber contrast of the darkest tenth of its pixels (the furrows and
the shaded brow heads) against the disk's median skin, (Y_median − Y_dark) / Y_median, on
relative luminance (linear sRGB, Rec. 709); "gain" is angry minus neutral — what the
expression adds to the region. A preset whose gain is much below the light preset's shows
the furrows faintly.

``python benchmarks/bench_furrows.py`` prints the table (docs/appearance.md, "Anger's furrows").
"""

from __future__ import annotations

import numpy as np

import emogen
from benchmarks.bench_contrast import PRESET_NAMES, luminance
from emogen.appearance.identities import PRESETS
from emogen.correct.faces import evaluate_corrected
from emogen.render.renderer import Renderer

SIZES = (512, 256)
RADIUS_CM = 0.55


def _glabella_contrast(y: np.ndarray, centre: np.ndarray, radius_px: float) -> float:
    rows, cols = np.mgrid[: y.shape[0], : y.shape[1]]
    mask = (cols + 0.5 - centre[0]) ** 2 + (rows + 0.5 - centre[1]) ** 2 <= radius_px**2
    values = np.sort(y[mask])
    dark = values[: max(1, round(0.1 * len(values)))].mean()
    median = float(np.median(values))
    return float((median - dark) / median)


def measure(preset: str, model: emogen.FaceModel) -> dict[str, float]:
    ident = PRESETS[preset]
    m = model.with_identity(ident.shape)
    angry = m.rig.weights_from_names({g: 1.0 for g in m.rig.emotions["angry"].core})
    w = np.stack([np.zeros(m.n_shapes), angry])
    v = evaluate_corrected(m, w[1:])[0]
    lm = m.landmarks
    up = np.array([0.0, 1.0, 0.0])
    centre = (v[lm[21]] + v[lm[22]]) / 2 + 0.35 * up
    out: dict[str, float] = {}
    for size in SIZES:
        with Renderer(m, size=size, appearance=ident.appearance, framing="face") as r:
            images = r.render(w, correct=True)
            camera = r.look.camera
        pts = camera.project(np.stack([centre, centre + RADIUS_CM * up]), size)
        radius_px = float(np.linalg.norm(pts[1] - pts[0]))
        neutral, ang = (_glabella_contrast(luminance(im), pts[0], radius_px) for im in images)
        out[f"neutral {size}"], out[f"angry {size}"] = neutral, ang
        out[f"gain {size}"] = ang - neutral
    return out


def main() -> None:
    model = emogen.load_model()
    rows = {p: measure(p, model) for p in PRESET_NAMES}
    keys = list(next(iter(rows.values())))
    print("Glabella: Weber contrast, darkest tenth vs median skin, face framing")
    print("| preset | " + " | ".join(keys) + " |")
    print("|---" * (len(keys) + 1) + "|")
    for p, r in rows.items():
        print(f"| {p} | " + " | ".join(f"{r[k]:.3f}" for k in keys) + " |")
    for sex in ("female", "male"):
        light = rows[f"{sex}-light"]
        for name in (f"{sex}-dark", f"{sex}-dark-v2", f"{sex}-dark-v3"):
            ratios = [rows[name][f"gain {s}"] / light[f"gain {s}"] for s in SIZES]
            print(
                f"{name} gain: "
                + ", ".join(
                    f"{q:.2f} × {sex}-light's at {s}²" for q, s in zip(ratios, SIZES, strict=True)
                )
            )


if __name__ == "__main__":
    main()
