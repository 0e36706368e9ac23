"""Weight vectors for rendering: CSV files of faces and short labels."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from emogen.model.face_table import read_face_table
from emogen.model.rig import Rig

LABEL_COLUMNS = ("label", "name")


def read_weights_csv(path: str | Path, rig: Rig) -> tuple[np.ndarray, list[str]]:
    """Faces from a CSV file: a header of shape or gene names (any subset; an optional ``label``
    or ``name`` column), one face per row; an empty cell is no weight. Returns (weights
    (n_faces, n_shapes), labels); a face without a label is described by its largest weights."""
    table = read_face_table(
        path,
        rig,
        what="--weights",
        others="error",
        label_columns=LABEL_COLUMNS,
        blank="zero",
        unit_range=True,
    )
    labels = [
        label or describe({c: float(v) for c, v in zip(table.columns, row, strict=True) if v == v})
        for label, row in zip(table.labels, table.values, strict=True)
    ]
    return table.weights, labels


def describe(named: dict[str, float], limit: int = 3) -> str:
    """A short label: the largest weights, e.g. ``"jawOpen 1, mouthSmile .5"``; ``"neutral"``."""
    items = sorted(((k, v) for k, v in named.items() if v), key=lambda kv: -abs(kv[1]))
    if not items:
        return "neutral"
    text = ", ".join(f"{k} {v:.2g}".replace(" 0.", " .") for k, v in items[:limit])
    return text + (" …" if len(items) > limit else "")
