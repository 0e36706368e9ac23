"""Render the six identity presets in a grid (docs/images/identities.png).

Female and male shapes (rows) at the light, medium and dark Monk skin tones (columns, MST 2, 5
and 8), each with its preset appearance, through the offscreen renderer (the look participants
see). Run: python scripts/identity_sheet.py [MODEL] [OUT.png] [SIZE]
"""

from __future__ import annotations

import sys

import numpy as np

import emogen
from emogen.appearance.identities import PRESETS
from emogen.render.images import contact_sheet, save_png
from emogen.render.renderer import Renderer

NAMES = [f"{sex}-{tone}" for sex in ("female", "male") for tone in ("light", "medium", "dark")]


def main() -> None:
    path = (sys.argv[1] if len(sys.argv) > 1 else "") or None  # "": $EMOGEN_MODEL
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/images/identities.png"
    size = int(sys.argv[3]) if len(sys.argv) > 3 else 256
    base = emogen.load_model(path)
    images, labels = [], []
    for name in NAMES:
        identity = PRESETS[name]
        model = base.with_identity(identity.shape)
        with Renderer(model, size=size, appearance=identity.appearance) as r:
            images.append(r.render(np.zeros((1, model.n_shapes)))[0])
        labels.append(f"{name} (MST {identity.appearance.skin_tone:g})")
    sheet = contact_sheet(np.stack(images), labels, columns=3)
    save_png(out, sheet, {"Software": f"EmoGen {emogen.__version__}"})


if __name__ == "__main__":
    main()
