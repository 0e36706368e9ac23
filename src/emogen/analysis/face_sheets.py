"""Mean-face error heatmaps (Fig. 9 and the like) with :mod:`emogen.render`.

Each panel is a face coloured by the per-vertex distance (cm) to a reference face — the mean
evolved face against its target, or a group's mean face against the neutral — and the panels
of one figure share one colour scale, so they compare at a glance. The sheet carries the
ICT-FaceKit notice. Faces are blended from their shape weights (correctives, if recorded, are
not re-applied), with the gaze rotation, as the renderer draws them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis import plots
from emogen.errors import ShapeError

if TYPE_CHECKING:
    from emogen.appearance.identities import Identity
    from emogen.model.face import FaceModel


@dataclass(frozen=True)
class Panel:
    """One heatmap: ``face`` against ``reference``, full weights in the model's shape order."""

    label: str
    face: np.ndarray
    reference: np.ndarray


def model_weights(
    weights: np.ndarray, columns: list[str] | tuple[str, ...], model: FaceModel
) -> np.ndarray:
    """Weights over ``columns`` (…, C) → the model's shape order (…, S); other columns dropped."""
    w = np.asarray(weights, dtype=np.float64)
    index = {c: i for i, c in enumerate(columns)}
    missing = [s for s in model.shape_names if s not in index]
    if len(missing) == len(model.shape_names):
        raise ShapeError("none of the weight columns is a shape of the model")
    out = np.zeros((*w.shape[:-1], model.n_shapes))
    for j, s in enumerate(model.shape_names):
        if s in index:
            out[..., j] = w[..., index[s]]
    return out


def heatmap_sheet(
    model: FaceModel,
    panels: list[Panel],
    path: Path,
    *,
    size: int = 256,
    columns: int = 4,
    vmax: float | None = None,
) -> pd.DataFrame:
    """Render the panels as one contact sheet (PNG at ``path``); returns per panel the RMS
    (eq. 13, all vertices) and the largest distance over the coloured parts (skin, mouth,
    teeth; cm) of the face to its reference, and the shared scale's top."""
    from emogen.render import Renderer, contact_sheet, render_heatmap
    from emogen.render.distance_map import HEAT_PARTS, nice_ceiling, vertex_distances

    faces = model.evaluate(np.stack([p.face for p in panels]).astype(np.float32))
    refs = model.evaluate(np.stack([p.reference for p in panels]).astype(np.float32))
    dist = vertex_distances(faces, refs)
    with Renderer(model, size=size) as r:
        names = [p.name for p in r.look.parts]
        coloured = np.isin(
            r.mesh.part.astype(int), [names.index(n) for n in HEAT_PARTS if n in names]
        )
        largest = dist[:, coloured].max(axis=1)
        top = vmax if vmax is not None else nice_ceiling(float(largest.max()))
        images = [
            render_heatmap(r, f, ref, vmax=top, footer="").image
            for f, ref in zip(faces, refs, strict=True)
        ]
        sheet = contact_sheet(
            np.stack(images),
            [p.label for p in panels],
            columns=columns,
            background=r.look.background_srgb,
        )
    stats = pd.DataFrame(
        {
            "panel": [p.label for p in panels],
            "rms_cm": np.sqrt((dist**2).mean(axis=1)),
            "max_cm": largest,
            "scale_top_cm": top,
        }
    )
    plots.save_image(path, sheet)
    return stats


def face_sheet(
    model: FaceModel,
    weights: np.ndarray,
    labels: list[str],
    path: Path,
    *,
    size: int = 256,
    columns: int = 4,
    identities: Sequence[Identity | None] | None = None,
) -> Path:
    """A contact sheet of faces (prototypes, mean faces) with labels and the licence notice;
    ``identities``: the identity (shape and appearance) each face is drawn on, as participants
    saw it (None: the model's own head)."""
    from emogen.render.images import contact_sheet

    images, background = render_on_identities(model, weights, identities, size=size)
    sheet = contact_sheet(images, labels, columns=columns, background=background)
    return plots.save_image(path, sheet)


def render_on_identities(
    model: FaceModel,
    weights: np.ndarray,
    identities: Sequence[Identity | None] | None,
    *,
    size: int,
) -> tuple[np.ndarray, Sequence[float] | None]:
    """(n, size, size, 3) images of faces ``weights`` (n, S), each on its identity (one
    renderer per identity), and the look's background colour."""
    from emogen.render import Renderer

    w = np.asarray(weights, dtype=np.float32)
    per_face = identities if identities is not None else [None] * len(w)
    images = np.zeros((len(w), size, size, 3), dtype=np.uint8)
    background: Sequence[float] | None = None
    for key in dict.fromkeys(id(i) for i in per_face):
        rows = np.array([j for j, i in enumerate(per_face) if id(i) == key])
        ident = per_face[int(rows[0])]
        m = model if ident is None else model.with_identity(ident.shape)
        appearance = None if ident is None else ident.appearance
        with Renderer(m, size=size, appearance=appearance) as r:
            images[rows] = r.render(w[rows])
            background = r.look.background_srgb
    return images, background
