"""Combinational correctives: shapes activated by the product of their drivers' weights.

A combinational corrective C with drivers (i, j, …) adds ``w_i · w_j · … · ΔC`` to the face. Its
weight is computed after the core weights and is never evolved (paper Section III-A).

ICT-FaceKit ships none, so EmoGen derives them from the geometry by one rule, **double
counting**: where two shapes push the same vertices the same way, their sum at full weight
moves those vertices by both amounts (an eyelid lowered twice, a cheek raised twice). Per
vertex, with u and w the two shapes' offsets, p = |u|², q = |w|²,

    o = (u·w)₊ / max(p, q) · (p u + q w) / (p + q)

is the part counted twice: along the direction of the larger offset, as long as the smaller
one's projection on it (exactly min(a, b) for parallel offsets a and b), blended smoothly so
that no crease appears where the two are equally long. The corrective is ΔC = −o, so at full
weight the pair moves each vertex about as far as the larger of the two alone. A pair gets a
corrective when its **overlap score** ‖o‖ / min(‖u‖, ‖w‖) — the share of the smaller shape
that is double counted — reaches the rig's threshold. Pairs never considered: shapes of one
gene (a left/right pair is designed to add up), left with right, excluded shapes, and the
jaw's articulations (other shapes are sculpted relative to the jaw, so their overlap with it
is by design, not double counting).

Companions: a shape that only makes sense together with another (ICT's ``mouthClose`` closes
the lips over an open jaw; alone it drives the lips through each other) has its effective
weight capped at its lead's: ``w_mouthClose ← min(w_mouthClose, w_jawOpen)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.model.rig import Rig

JAW_SHAPES = ("jawOpen", "jawForward", "jawLeft", "jawRight")


@dataclass(frozen=True)
class DerivedPair:
    """A derived corrective: its drivers (shape names), overlap score and peak offset (cm)."""

    drivers: tuple[str, str]
    score: float
    peak: float


def double_counted(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The double-counted offset o (V, 3) of two shapes' offsets u, w (V, 3) (module docstring)."""
    u = np.asarray(u, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    p = np.einsum("vd,vd->v", u, u)
    q = np.einsum("vd,vd->v", w, w)
    dot = np.maximum(np.einsum("vd,vd->v", u, w), 0.0)
    den = np.maximum(p, q) * (p + q)
    scale = np.divide(dot, den, out=np.zeros_like(dot), where=den > 0)
    return scale[:, None] * (p[:, None] * u + q[:, None] * w)


def _norm(x: np.ndarray) -> float:
    """Frobenius norm without BLAS (its threads stall on a busy machine for small vectors)."""
    x = np.asarray(x, dtype=np.float64)
    return float(np.sqrt(np.sum(x * x)))


def overlap_score(u: np.ndarray, w: np.ndarray, o: np.ndarray | None = None) -> float:
    """‖o‖ / min(‖u‖, ‖w‖): the share of the smaller shape that the pair counts twice."""
    o = double_counted(u, w) if o is None else o
    small = min(_norm(u), _norm(w))
    return _norm(o) / small if small > 0 else 0.0


def _side(name: str) -> str:
    return name[-1] if name.endswith(("_L", "_R")) else "C"


def candidate_pairs(rig: Rig) -> list[tuple[str, str]]:
    """Shape pairs the double-counting rule considers (see the module docstring)."""
    gene_of = {s: g.name for g in rig.genes for s in g.shapes}
    shapes = [
        s for s in rig.shape_names if s in gene_of and s not in rig.excluded and s not in JAW_SHAPES
    ]
    out = []
    for i, a in enumerate(shapes):
        for b in shapes[i + 1 :]:
            if gene_of[a] == gene_of[b] or {_side(a), _side(b)} == {"L", "R"}:
                continue
            out.append((a, b))
    return out


def mirror(name: str) -> str:
    """``X_L`` ↔ ``X_R``; other names unchanged."""
    if name.endswith("_L"):
        return name[:-2] + "_R"
    if name.endswith("_R"):
        return name[:-2] + "_L"
    return name


def derive_pairs(
    deltas: np.ndarray, shape_names: tuple[str, ...], rig: Rig, min_score: float
) -> list[tuple[DerivedPair, np.ndarray]]:
    """Pairs whose overlap score reaches ``min_score``, each with its corrective (V, 3) float32.

    A pair and its mirror image (left ↔ right) are judged together, by their mean score, so the
    set is symmetric like the faces. Deterministic: candidates in shape order, results sorted
    by score (highest first), then by name.
    """
    index = {s: i for i, s in enumerate(shape_names)}
    norms = np.sqrt(np.einsum("svd,svd->sv", deltas, deltas, dtype=np.float64))
    total = np.sqrt((norms**2).sum(1))
    pairs = candidate_pairs(rig)

    def twin_of(pair: tuple[str, str]) -> tuple[str, str]:
        a, b = sorted((mirror(pair[0]), mirror(pair[1])), key=index.__getitem__)
        return (a, b)

    # |o| ≤ min(|u|, |w|) per vertex bounds the score; skip pairs that, even with their mirror
    # twin, cannot reach the threshold.
    bound = {}
    for a, b in pairs:
        small = min(total[index[a]], total[index[b]])
        tight = _norm(np.minimum(norms[index[a]], norms[index[b]]))
        bound[(a, b)] = float(tight / small) if small > 0 else 0.0
    scored: dict[tuple[str, str], tuple[float, np.ndarray]] = {}
    for pair in pairs:
        twin = twin_of(pair)
        if bound[pair] + bound.get(twin, bound[pair]) < 2 * min_score:
            continue
        i, j = index[pair[0]], index[pair[1]]
        both = np.flatnonzero((norms[i] > 0) & (norms[j] > 0))  # o is zero elsewhere
        o = np.zeros(deltas.shape[1:])
        o[both] = double_counted(deltas[i, both], deltas[j, both])
        small = min(total[i], total[j])
        scored[pair] = (_norm(o) / small if small > 0 else 0.0, o)
    found = []
    for (a, b), (score, o) in scored.items():
        twin = twin_of((a, b))
        twin_score = scored[twin][0] if twin in scored else score
        if (score + twin_score) / 2 >= min_score:
            peak = float(np.sqrt(np.einsum("vd,vd->v", o, o).max()))
            found.append((DerivedPair((a, b), round(score, 6), peak), (-o).astype(np.float32)))
    found.sort(key=lambda t: (-t[0].score, t[0].drivers))
    return found


def activations(weights: np.ndarray, drivers: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Product activations: weights (B, S) → (B, C).

    drivers : (C, K) int, padded; mask : (C, K) bool, which entries are real drivers. A
    corrective's activation is the product of its drivers' weights.
    """
    w = np.asarray(weights, dtype=np.float64)
    if drivers.shape[0] == 0:
        return np.zeros((len(w), 0))
    picked = w[:, drivers]  # (B, C, K)
    return np.where(mask[None], picked, 1.0).prod(axis=2)
