"""The eyes close up, before and after: `python scripts/eyes_close_up.py OUT.png --before SRC`.

Renders the eye region of a light and a dark preset (neutral, 1024² face framing, corrected)
with this tree's renderer ("after") and with the source tree SRC ("before", e.g. a checkout of
main's ``src``, in a subprocess), side by side with captions.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
PRESETS = ("female-light", "male-dark")
SIZE = 1024
CROP = (slice(int(0.27 * SIZE), int(0.47 * SIZE)), slice(int(0.21 * SIZE), int(0.79 * SIZE)))


def crops() -> np.ndarray:
    """(rows·h, w, 3) uint8: the eye region of each preset, stacked."""
    from emogen.appearance.identities import PRESETS as LOOKS
    from emogen.model import load_model
    from emogen.render.renderer import Renderer

    model = load_model(None)
    w = np.zeros((1, model.n_shapes), dtype=np.float32)
    rows = []
    for name in PRESETS:
        with Renderer(model, size=SIZE, appearance=LOOKS[name].appearance) as r:
            rows.append(r.render(w, correct=True)[0][CROP])
    return np.concatenate(rows, 0)


def _before(src: str) -> np.ndarray:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "before.npy"
        env = {**os.environ, "PYTHONPATH": src}
        subprocess.run(
            [sys.executable, __file__, "--crops", str(out)], env=env, check=True, cwd=tmp
        )
        return np.load(out)


def _panel(image: np.ndarray, caption: str) -> np.ndarray:
    from PIL import Image, ImageDraw

    head = Image.new("RGB", (image.shape[1], 24), "white")
    ImageDraw.Draw(head).text((4, 5), caption, fill="black")
    return np.concatenate([np.asarray(head), image], 0)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path, help="PNG to write (or, with --crops, .npy)")
    ap.add_argument("--before", help="source tree of the 'before' renderer, e.g. main's src")
    ap.add_argument("--crops", action="store_true", help="write this tree's crops as .npy")
    ap.add_argument("--caption", default="after: caruncle, wet lower lid margin, catchlights")
    args = ap.parse_args()
    if args.crops:
        np.save(args.out, crops())
        return
    from PIL import Image

    after = _panel(crops(), args.caption)
    panels = [after]
    if args.before:
        panels.insert(0, _panel(_before(args.before), "before (main)"))
    gap = np.full((after.shape[0], 12, 3), 255, dtype=np.uint8)
    Image.fromarray(
        np.concatenate([panels[0], *(x for p in panels[1:] for x in (gap, p))], 1)
    ).save(args.out)


if __name__ == "__main__":
    if "--crops" not in sys.argv:  # the 'before' run keeps its own PYTHONPATH
        sys.path.insert(0, str(REPO / "src"))
    main()
