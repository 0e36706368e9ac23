"""Weight vectors for rendering: CSV files of faces and short labels."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from emogen.errors import ConfigError, ShapeError
from emogen.model.rig import Rig

LABEL_COLUMNS = ("label", "name")


def read_weights_csv(path: str | Path, rig: Rig) -> tuple[np.ndarray, list[str]]:
    """Faces from a CSV file: a header of shape or gene names (any subset; an optional ``label``
    or ``name`` column), one face per row. Returns (weights (n_faces, n_shapes), labels)."""
    p = Path(path)
    try:
        with p.open(newline="", encoding="utf-8-sig") as fh:
            rows = list(csv.DictReader(fh))
    except OSError as exc:
        raise ConfigError(f"--weights {p}: {exc.strerror}") from None
    if not rows:
        raise ConfigError(f"--weights {p}: no faces (expected a header row and one row per face)")
    weights, labels = [], []
    for line, row in enumerate(rows, start=2):
        named: dict[str, float] = {}
        label = ""
        for key, value in row.items():
            if key is None:
                raise ConfigError(f"--weights {p} line {line}: more values than header columns")
            key = key.strip()
            if key.lower() in LABEL_COLUMNS:
                label = (value or "").strip()
                continue
            if value is None or not value.strip():
                continue
            try:
                named[key] = float(value)
            except ValueError:
                raise ConfigError(
                    f"--weights {p} line {line}: column {key!r} value {value!r} is not a number"
                ) from None
        try:
            weights.append(rig.weights_from_names(named))
        except ConfigError as exc:
            raise ConfigError(f"--weights {p} line {line}: {exc}") from None
        except ShapeError as exc:
            raise ShapeError(f"--weights {p} line {line}: {exc}") from None
        labels.append(label or describe(named))
    return np.asarray(weights), labels


def describe(named: dict[str, float], limit: int = 3) -> str:
    """A short label: the largest weights, e.g. ``"jawOpen 1, mouthSmile .5"``; ``"neutral"``."""
    items = sorted(((k, v) for k, v in named.items() if v), key=lambda kv: -abs(kv[1]))
    if not items:
        return "neutral"
    text = ", ".join(f"{k} {v:.2g}".replace(" 0.", " .") for k, v in items[:limit])
    return text + (" …" if len(items) > limit else "")
