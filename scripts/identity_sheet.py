"""Draw the generic, male and female identities side by side (docs/images/identities.png).

A plain matplotlib preview (depth-sorted, Lambert-shaded triangles) used until the real
renderer exists; run: python scripts/identity_sheet.py [MODEL] [OUT.png]
"""

from __future__ import annotations

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import PolyCollection

import emogen

PARTS = ("face", "head_neck", "eyeball_left", "eyeball_right", "eyelashes_left", "eyelashes_right")


def draw(ax, model, weights=None) -> None:  # type: ignore[no-untyped-def]
    w = np.zeros((1, model.n_shapes)) if weights is None else weights[None]
    v = model.evaluate(w)[0].astype(np.float64)
    keep = np.zeros(len(model.polygons), bool)
    for p in PARTS:
        keep[model.regions[p].polygons] = True
    tris = model.faces[
        keep[np.repeat(np.arange(len(model.polygons)), 1 + (model.polygons[:, 3] >= 0))]
    ]
    t = v[tris]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-12
    front = n[:, 2] > 0
    t, n = t[front], n[front]
    light = np.array([0.3, 0.4, 1.0])
    shade = np.clip(n @ (light / np.linalg.norm(light)), 0, 1) * 0.8 + 0.15
    order = np.argsort(t[:, :, 2].mean(1))
    colours = np.c_[shade[order, None] * np.array([[0.93, 0.78, 0.68]]), np.ones(len(order))]
    ax.add_collection(PolyCollection(t[order][:, :, :2], facecolors=colours, edgecolors="none"))
    ax.set_xlim(-13, 13)
    ax.set_ylim(-16, 14)
    ax.set_aspect("equal")
    ax.axis("off")


def main() -> None:
    path = sys.argv[1] if len(sys.argv) > 1 else None
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/images/identities.png"
    base = emogen.load_model(path)
    fig, axes = plt.subplots(1, 3, figsize=(9, 3.6), dpi=110)
    for ax, ident in zip(axes, ("generic", "male", "female"), strict=True):
        draw(ax, base.with_identity(ident))
        ax.set_title(ident)
    fig.text(0.5, 0.01, "ICT-FaceKit © 2020 USC ICT (MIT licence)", ha="center", fontsize=7)
    fig.tight_layout()
    fig.savefig(out)


if __name__ == "__main__":
    main()
