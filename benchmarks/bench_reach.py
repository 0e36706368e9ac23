"""The rig's reach: landmark displacements (mm) of every expression gene at weight 1.

For each gene (both sides of a pair at 1, corrected as a study shows it) and for each emotion
prototype (its core block at 1), the displacement of ICT's Multi-PIE landmarks on the generic
face, with an older rig (``--before``: rig 2, reach shapes version 1, or rig 1, none) and rig 3
(today's default):

* ``brow in`` / ``brow out``: vertical motion of the inner (21, 22) and outer (17, 26) brow
  points, + up; ``knit``: change of the gap between the inner brow points, − drawn together;
* ``upper lid`` / ``lower lid``: vertical motion of the lid points (37, 38, 43, 44 and 40, 41,
  46, 47), + up; ``aperture``: change of their distance, − narrower;
* ``corner x`` / ``corner y``: the mouth corners (48, 54), x outward, y up;
* ``lips``: change of the inner-lip separation (62–66);
* ``red``: change of the red lips' summed height, upper (51–62) and lower (66–57), − thinner;
* ``fold``: nasolabial relief, the forward motion of the cheek 1 cm lateral to the fold line
  minus that on the line (a point a third of the way from the ala, 31/35, to the corner,
  shifted 0.5 cm sideways): + a deeper fold.

``python benchmarks/bench_reach.py [--before 2|1]`` prints the table (docs/model.md, "Reach").
"""

from __future__ import annotations

import argparse
from importlib import resources

import numpy as np

import emogen
from emogen.correct import correct_faces, corrected_vertices

SIDES = ((+1, {"brow_in": 22, "brow_out": 26, "ala": 35, "corner": 54}),
         (-1, {"brow_in": 21, "brow_out": 17, "ala": 31, "corner": 48}))  # fmt: skip
UPPER_LID, LOWER_LID = (37, 38, 43, 44), (40, 41, 46, 47)
COLUMNS = ("brow in", "brow out", "knit", "upper lid", "lower lid", "aperture",
           "corner x", "corner y", "lips", "red", "fold")  # fmt: skip
GENES = (
    "browDown", "browInnerUp", "browOuterUp", "eyeWide", "eyeSquint", "eyeBlink", "cheekSquint",
    "cheekRaiser", "noseSneer", "mouthSmile", "mouthDimple", "mouthStretch", "mouthFrown",
    "mouthPress", "mouthUpperUp", "mouthLowerDown", "mouthShrugUpper", "mouthShrugLower",
    "mouthFunnel", "mouthPucker", "mouthRollUpper", "mouthRollLower", "cheekPuff", "jawOpen",
    "jawForward",
)  # fmt: skip


def _fold_points(model: emogen.FaceModel) -> list[tuple[int, int, int]]:
    """(side, vertex on the fold line, vertex 1 cm lateral of it) per side, on the face mesh."""
    n = model.base_neutral.astype(np.float64)
    face = model.regions["face"]
    front = np.arange(face.v_start, face.v_stop)
    front = front[n[front, 2] > n[model.landmarks[54], 2] - 2.0]
    out = []
    for s, lm in SIDES:
        ala, corner = n[model.landmarks[lm["ala"]]], n[model.landmarks[lm["corner"]]]
        line = ala + (corner - ala) / 3 + np.array([s * 0.5, 0.0, 0.0])
        cheek = line + np.array([s * 1.0, 0.0, 0.0])
        near = [
            int(front[np.argmin(np.linalg.norm(n[front, :2] - p[:2], axis=1))])
            for p in (line, cheek)
        ]
        out.append((s, near[0], near[1]))
    return out


def measures(model: emogen.FaceModel, weights: np.ndarray) -> np.ndarray:
    """(B, 11) the columns above in mm for faces (B, S), corrected."""
    v = corrected_vertices(model, correct_faces(model, weights), gaze=False).astype(np.float64)
    n = model.base_neutral.astype(np.float64)
    lm = model.landmarks
    d = v - n
    out = np.zeros((len(v), len(COLUMNS)))
    out[:, 0] = d[:, lm[[21, 22]], 1].mean(1)
    out[:, 1] = d[:, lm[[17, 26]], 1].mean(1)
    out[:, 2] = (v[:, lm[22], 0] - v[:, lm[21], 0]) - (n[lm[22], 0] - n[lm[21], 0])
    out[:, 3] = d[:, lm[list(UPPER_LID)], 1].mean(1)
    out[:, 4] = d[:, lm[list(LOWER_LID)], 1].mean(1)
    out[:, 5] = out[:, 3] - out[:, 4]
    corner_x = [s * d[:, lm[side["corner"]], 0] for s, side in SIDES]
    out[:, 6] = np.mean(corner_x, axis=0)
    out[:, 7] = d[:, lm[[48, 54]], 1].mean(1)
    gap = lambda x: np.linalg.norm(x[..., lm[62], :] - x[..., lm[66], :], axis=-1)  # noqa: E731
    out[:, 8] = gap(v) - gap(n)
    red = lambda x: x[..., lm[51], 1] - x[..., lm[62], 1] + x[..., lm[66], 1] - x[..., lm[57], 1]  # noqa: E731
    out[:, 9] = red(v) - red(n)
    out[:, 10] = np.mean([d[:, c, 2] - d[:, f, 2] for _, f, c in _fold_points(model)], axis=0)
    return out * 10.0  # cm → mm


def rig_models(before: int) -> tuple[emogen.FaceModel, emogen.FaceModel]:
    """(the older packaged rig ``before``, today's rig 3)."""
    file = f"ict_rig_{before}.toml"
    with resources.as_file(resources.files("emogen.data").joinpath(file)) as p:
        old = emogen.load_model(rig=p)
    return old, emogen.load_model()


def rows(model: emogen.FaceModel) -> tuple[list[str], np.ndarray]:
    names, faces = [], []
    for g in GENES:
        names.append(g)
        faces.append(model.rig.weights_from_names({g: 1.0}))
    for e, block in model.rig.emotions.items():
        names.append(f"**{e}** ({'+'.join(block.core)})")
        faces.append(model.rig.weights_from_names({g: 1.0 for g in block.core}))
    return names, measures(model, np.asarray(faces))


def _cell(a: float, b: float) -> str:
    if abs(a) < 0.05 and abs(b) < 0.05:
        return ""
    return f"{a:.1f}" if abs(a - b) < 0.05 else f"{a:.1f} → **{b:.1f}**"


def table(older: int) -> str:
    old_model, new_model = rig_models(older)
    names1, old = rows(old_model)
    names2, new = rows(new_model)
    lines = [
        "| shape (weight 1) | " + " | ".join(COLUMNS) + " |",
        "|---" * (len(COLUMNS) + 1) + "|",
    ]
    for i, name in enumerate(names2):
        j = names1.index(name) if name in names1 else None
        before = old[j] if j is not None else np.full(len(COLUMNS), np.nan)
        if j is None:  # a prototype whose block changed: its older rig's row is separate
            k = next(k for k, n1 in enumerate(names1) if n1.split(" ")[0] == name.split(" ")[0])
            lines.append(
                f"| {names1[k]} (rig {older}) | " + " | ".join(_cell(x, x) for x in old[k]) + " |"
            )
            before = new[i]
        lines.append(
            f"| {name} | "
            + " | ".join(_cell(a, b) for a, b in zip(before, new[i], strict=True))
            + " |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--before", type=int, choices=(1, 2), default=2, help="older rig")
    args = parser.parse_args()
    print(
        f"mm at weight 1, generic face, corrected; 'a → b': rig {args.before} → rig 3 "
        "(blank: < 0.05 mm)"
    )
    print(table(args.before))


if __name__ == "__main__":
    main()
