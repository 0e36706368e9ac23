"""Write the packaged sample of fixed initialisations, src/emogen/data/fixed_init.toml (run once).

Three sets of ten faces laid out like a protocol-generated population (two faces each of
happy, sad, angry and fearful from the rig's building blocks, one surprised or disgusted face,
one neutral) but fixed, and of increasing complexity, like the paper's fixed initialisations
no. 1 (simple) and no. 3 (complex): set 1 has 1-3 genes per face, set 2 has 3-6, set 3 has
8-12 (drawn from all non-eye genes beyond the emotion's blocks). No face uses ``jawOpen``, so
a jaw-open target is not biased towards the sample (as the paper's target 1 was not).
Values are rounded to 0.05 in [0.2, 0.9] so that every activation is visible.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import emogen

SEED = 20261205
RANGES = {1: (1, 3), 2: (3, 6), 3: (8, 12)}
LAYOUT = ["happy", "happy", "sad", "sad", "angry", "angry", "fearful", "fearful", "surprised"]
DESCRIPTIONS = {
    1: "simple: 1-3 genes per face",
    2: "moderate: 3-6 genes per face",
    3: "complex: 8-12 genes per face",
}


def face(rig, emotion: str, n: int, rng: np.random.Generator) -> dict[str, float]:
    spec = rig.emotions[emotion]
    others = [g for g in rig.gene_names(False) if g != "jawOpen"]
    blocks = [g for g in (*spec.core, *spec.optional) if g != "jawOpen" and g in others]
    order = list(rng.permutation(blocks))
    order += list(rng.permutation([g for g in others if g not in order]))
    values = np.round(rng.uniform(0.2, 0.9, size=n) * 20) / 20
    return {str(g): float(v) for g, v in zip(order[:n], values, strict=True)}


def main() -> None:
    rig = emogen.load_model(sys.argv[1] if len(sys.argv) > 1 else None).rig
    rng = np.random.default_rng(SEED)
    lines = [
        "# Fixed initialisations for EmoGen's GA: three sets of ten faces (gene or shape weights).",
        "# Written by scripts/make_fixed_init.py; see its docstring for how they were made.",
        "# No face uses jawOpen. An omitted gene is 0; {} is the neutral face.",
        'description = "Sample fixed initialisations (simple, moderate, complex)"',
    ]
    for number, (lo, hi) in RANGES.items():
        lines += ["", "[[sets]]", f'description = "{DESCRIPTIONS[number]}"', "faces = ["]
        layout = [*LAYOUT[:-1], "surprised" if number != 2 else "disgusted"]
        for emotion in layout:
            named = face(rig, emotion, int(rng.integers(lo, hi + 1)), rng)
            body = ", ".join(f"{k} = {v:g}" for k, v in named.items())
            lines.append(f"  {{{body}}},  # {emotion}")
        lines += ["  {},  # neutral", "]"]
    out = Path(__file__).resolve().parents[1] / "src" / "emogen" / "data" / "fixed_init.toml"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
