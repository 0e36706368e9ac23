"""Luminance contrast of brows, lips and lip line per identity preset, on the study background.

Each preset's neutral face is rendered as participants see it (512², ``face`` framing, the
look's grey background) and sampled in small disks (radius 1.5% of the image) around points
projected from ICT's landmarks of that identity:

* **brow**: the brow band — landmarks 18–20 and 23–25 lowered 0.05 cm (where the painted brow
  sits, checked on the images); **forehead**: the same points 1.2 cm higher;
* **lip**: the vermilion midway between the outer lip line and the mouth line (landmarks 50,
  52, 56, 58 moved 40% towards 62/66); **skin by the lips**: 0.7 cm above the upper lip's and
  below the lower lip's outer line;
* **mouth line**: the darkest tenth of the pixels in disks on the mouth line (landmarks 61–63,
  65–67: the line is one or two pixels wide) against the vermilion;
* **cheek** beside the nose (the midpoints of 31–2 and 35–14) against the **background**.

Figures are Weber contrasts of relative luminance (linear sRGB, Rec. 709 weights):
(Y_surround − Y_feature) / Y_surround, positive when the feature is darker.

``python benchmarks/bench_contrast.py`` prints the table (docs/appearance.md, "Contrast").
"""

from __future__ import annotations

import numpy as np

import emogen
from emogen.appearance.identities import PRESETS
from emogen.render.renderer import Renderer

PRESET_NAMES = tuple(
    f"{s}-{t}"
    for s in ("female", "male")
    for t in ("light", "medium", "dark", "dark-v2", "dark-v3")
)
SIZE = 512
RADIUS = 0.015  # of the image size


def luminance(image: np.ndarray) -> np.ndarray:
    """Relative luminance of sRGB uint8 pixels (…, 3)."""
    c = image.astype(np.float64) / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return lin @ np.array([0.2126, 0.7152, 0.0722])


def _disk_mean(y: np.ndarray, pixels: np.ndarray, darkest: float = 1.0) -> float:
    """Mean luminance in disks round ``pixels``; of their darkest ``darkest`` share only."""
    rows, cols = np.mgrid[: y.shape[0], : y.shape[1]]
    mask = np.zeros(y.shape, dtype=bool)
    r = RADIUS * y.shape[0]
    for px, py in pixels:
        mask |= (cols + 0.5 - px) ** 2 + (rows + 0.5 - py) ** 2 <= r * r
    values = np.sort(y[mask])
    return float(values[: max(1, round(darkest * len(values)))].mean())


def regions(n: np.ndarray, lm: np.ndarray) -> dict[str, np.ndarray]:
    """Points (cm) of each sampled region on the neutral ``n`` (V, 3)."""
    up = np.array([0.0, 1.0, 0.0])
    brow = n[lm[[18, 19, 20, 23, 24, 25]]] - 0.05 * up
    outer = n[lm[[50, 52, 56, 58]]]
    inner = n[lm[[62, 62, 66, 66]]]
    return {
        "brow": brow,
        "forehead": brow + 1.2 * up,
        "lip": outer + 0.4 * (inner - outer),
        "lip skin": np.vstack([n[lm[[50, 52]]] + 0.7 * up, n[lm[[56, 58]]] - 0.7 * up]),
        "lip line": n[lm[[61, 62, 63, 65, 66, 67]]],
        "cheek": (n[lm[[31, 35]]] + n[lm[[2, 14]]]) / 2,
    }


def measure(preset: str, model: emogen.FaceModel) -> dict[str, float]:
    ident = PRESETS[preset]
    m = model.with_identity(ident.shape)
    with Renderer(m, size=SIZE, appearance=ident.appearance, framing="face") as r:
        image = r.render(np.zeros((1, m.n_shapes)), correct=True)[0]
        camera = r.look.camera
        background = luminance(np.array(r.look.background_srgb) * 255.0)
    y = luminance(image)
    mean = {
        k: _disk_mean(y, camera.project(p, SIZE), 0.1 if k == "lip line" else 1.0)
        for k, p in regions(m.neutral, m.landmarks).items()
    }

    def weber(feature: str, surround: str) -> float:
        return (mean[surround] - mean[feature]) / mean[surround]

    return {
        "brow/forehead": weber("brow", "forehead"),
        "lip/skin": weber("lip", "lip skin"),
        "mouth line/lip": weber("lip line", "lip"),
        "cheek/background": (mean["cheek"] - float(background)) / float(background),
        "Y skin": mean["forehead"],
    }


def table() -> tuple[str, dict[str, dict[str, float]]]:
    model = emogen.load_model()
    rows = {p: measure(p, model) for p in PRESET_NAMES}
    keys = list(next(iter(rows.values())))
    lines = ["| preset | " + " | ".join(keys) + " |", "|---" * (len(keys) + 1) + "|"]
    for p, r in rows.items():
        lines.append(f"| {p} | " + " | ".join(f"{r[k]:.2f}" for k in keys) + " |")
    return "\n".join(lines), rows


def main() -> None:
    text, rows = table()
    print("Weber contrast of relative luminance, neutral face, 512², face framing")
    print(text)
    for sex in ("female", "male"):
        for dark_name in (f"{sex}-dark", f"{sex}-dark-v2", f"{sex}-dark-v3"):
            light, dark = rows[f"{sex}-light"], rows[dark_name]
            for k in ("brow/forehead", "lip/skin", "mouth line/lip"):
                print(f"{dark_name} {k}: {dark[k] / light[k]:.2f} × {sex}-light's")


if __name__ == "__main__":
    main()
