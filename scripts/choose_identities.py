"""Derive the `male` and `female` identity presets of the ICT rig (run once; prints TOML).

Rule (documented in docs/model.md): a sexual-dimorphism score is built from anthropometric
measurements known to differ between adult male and female faces (Farkas 1994; Bruce et al.
1993): lower-jaw (bigonial) width, lower-face height, nose width and length, and brow-ridge
projection over the eyes, each larger in men. Over 4,000 random identities β ~ N(0, I) the
measurements are standardised and summed; the score's least-squares gradient in β is the
dimorphism direction u. The presets are β = ±2 u/|u|: two standard deviations of the
identity space along that direction (male +, female −).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

import emogen

SEED = 20261121


def measurements(verts: np.ndarray, lm: np.ndarray) -> np.ndarray:
    """verts (B, V, 3) → (B, 5) measurements in cm from Multi-PIE 68 landmarks."""
    p = verts[:, lm]
    dist = lambda a, b: np.linalg.norm(p[:, a] - p[:, b], axis=-1)  # noqa: E731
    jaw = dist(4, 12)  # bigonial-ish width
    lower_face = dist(33, 8)  # subnasale to chin
    nose_w = dist(31, 35)
    nose_l = dist(27, 33)
    brow = p[:, [19, 24], 2].mean(1) - p[:, [37, 44], 2].mean(1)  # brow projection (z)
    return np.stack([jaw, lower_face, nose_w, nose_l, brow], 1)


def main(folder: str) -> None:
    model = emogen.load_model(folder)
    lm = np.array(
        json.loads((Path(folder) / "vertex_indices.json").read_text())["idx_to_landmark_verts"]
    )
    rng = np.random.default_rng(SEED)
    k = model.n_identity_modes
    betas = rng.standard_normal((4000, k))
    base = model.base_neutral.reshape(-1)
    basis = model.identity_deltas.reshape(k, -1)
    verts = (base + betas.astype(np.float32) @ basis).reshape(len(betas), -1, 3)
    m = measurements(verts, lm)
    z = (m - m.mean(0)) / m.std(0)
    score = z.sum(1)
    design = np.c_[betas, np.ones(len(betas))]
    coef, *_ = np.linalg.lstsq(design, score, rcond=None)
    u = coef[:k] / np.linalg.norm(coef[:k])
    r2 = 1 - ((design @ coef - score) ** 2).sum() / ((score - score.mean()) ** 2).sum()
    for name, sign in (("male", 1.0), ("female", -1.0)):
        beta = sign * 2.0 * u
        vals = ", ".join(f"{b:.4f}" for b in beta)
        print(f"[identities.{name}]")
        print(f"coefficients = [{vals}]")
        print(
            f'description = "{"+" if sign > 0 else "-"}2 SD along the sexual-dimorphism direction of '
            f'the identity space (scripts/choose_identities.py, seed {SEED}, linear fit R²={r2:.2f})"'
        )
        print()
    print(f"# measurement means (cm): {np.round(m.mean(0), 3).tolist()}", file=sys.stderr)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "../shared/ict-facekit/FaceXModel")
