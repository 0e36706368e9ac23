"""The collision solve (paper eq. 5) and the detect–solve loop.

For one face with M intersection pairs (rows of δa, eqs. 3–4, and δb), the eight collision
weights minimise

    C = w₁ ‖A w − b‖² + (1 − w₁) M ‖w‖²,   w ∈ [0, 1]⁸,   w₁ = 0.98        (eq. 5)

Cross-type coefficients (a lip corrective's effect on a teeth pair and vice versa) are kept only
when both types collide. With both, the paper's alternation: while one type's constraints are
solved, the other type's jacobians are zeroed and its current contribution is a constant on the
right-hand side; the two types take turns (Gauss–Seidel) until the weights settle. Each solve is
``scipy.optimize.lsq_linear`` on the stacked system [√w₁ A; √((1−w₁)M) I] w ≈ [√w₁ b; 0].

Blendshapes are linear, so a pair's separation is exactly linear in w; what changes as the face
is corrected is which pairs the rays find (surfaces slide). The loop therefore re-detects on
the corrected face and solves eq. 5 again for an *increment* of the weights, bounded so that the
total stays in [0, 1], until no anchor is within the lower lip or ``max_iterations`` is
reached. Every collision corrective only ever moves the lips apart (δa ≥ 0 for every pair), so
an increment never undoes a pair an earlier round separated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from emogen.correct.blend import blend
from emogen.correct.collision import (
    LIP,
    TEETH,
    CollisionLayout,
    depth_jacobian,
    detect,
)

W1 = 0.98
MAX_ITERATIONS = 6
ALTERNATIONS = 8
DEPTH_MARGIN = 0.03  # cm added to every δb, so the regularised solution clears the contact
N_ZONES = 4


@dataclass(frozen=True)
class CollisionSolution:
    """weights : (B, 8) collision corrective weights in [0, 1]
    within_before, within_after : (B, 2) int, anchors within the lower lip (lip, teeth) on the
      face as given and after correction
    depth_after : (B,) float, the deepest remaining within pair (cm; 0 when none)
    iterations : (B,) int, detect–solve rounds used (0: no collision)
    """

    weights: np.ndarray
    within_before: np.ndarray
    within_after: np.ndarray
    depth_after: np.ndarray
    iterations: np.ndarray

    @property
    def collided(self) -> np.ndarray:
        return self.within_before.sum(1) > 0

    @property
    def remaining(self) -> np.ndarray:
        """(B,) bool: a collision is still detected after correction."""
        return self.within_after.sum(1) > 0


def _block_solve(a: np.ndarray, b: np.ndarray, reg: float, upper: np.ndarray) -> np.ndarray:
    """argmin_{0 ≤ w ≤ upper} w₁‖a w − b‖² + reg ‖w‖² (reg = (1 − w₁) M)."""
    n = a.shape[1]
    if not np.any(upper > 0):
        return np.zeros(n)
    lhs = np.vstack([np.sqrt(W1) * a, np.sqrt(reg) * np.eye(n)])
    rhs = np.concatenate([np.sqrt(W1) * b, np.zeros(n)])
    hi = np.maximum(upper, 1e-12)  # lsq_linear wants lower < upper
    return np.clip(lsq_linear(lhs, rhs, bounds=(np.zeros(n), hi), method="bvls").x, 0.0, upper)


def solve_eq5(
    a: np.ndarray, b: np.ndarray, kind: np.ndarray, upper: np.ndarray | None = None
) -> np.ndarray:
    """Collision weights (8,) for one face from its pairs: a (M, 8) δa, b (M,) δb, kind (M,).

    Columns 0–3 are the lip correctives, 4–7 the teeth ones; ``upper`` (8,) bounds the weights
    (default 1). A type without pairs keeps its correctives at 0. See the module docstring.
    """
    ub = np.ones(2 * N_ZONES) if upper is None else np.asarray(upper, dtype=np.float64)
    w = np.zeros(2 * N_ZONES)
    m = len(b)
    if m == 0:
        return w
    reg = (1.0 - W1) * m
    cols = {LIP: slice(0, N_ZONES), TEETH: slice(N_ZONES, 2 * N_ZONES)}
    present = [k for k in (LIP, TEETH) if np.any(kind == k)]
    both = len(present) == 2
    for _ in range(ALTERNATIONS if both else 1):
        before = w.copy()
        for k in present:
            rows = kind == k
            other = cols[TEETH if k == LIP else LIP]
            # The other type's jacobians are zeroed; its contribution is a constant (and is
            # counted only when both types collide).
            constant = a[rows][:, other] @ w[other] if both else 0.0
            w[cols[k]] = _block_solve(a[rows][:, cols[k]], b[rows] - constant, reg, ub[cols[k]])
        if np.max(np.abs(w - before)) < 1e-5:
            break
    return w


def solve_collisions(
    base_local: np.ndarray,
    deltas_local: np.ndarray,
    layout: CollisionLayout,
    *,
    max_iterations: int = MAX_ITERATIONS,
    margin: float = DEPTH_MARGIN,
) -> CollisionSolution:
    """Detect and correct collisions of a batch.

    base_local : (B, L, 3) float64 positions of ``layout.vertices`` before collision correction
    deltas_local : (8, L, 3) the collision correctives at those vertices
    """
    b_n = len(base_local)
    n_c = deltas_local.shape[0]
    flat_deltas = deltas_local.reshape(n_c, -1)
    weights = np.zeros((b_n, n_c))
    within_before = np.zeros((b_n, 2), dtype=np.int64)
    within_after = np.zeros((b_n, 2), dtype=np.int64)
    depth_after = np.zeros(b_n)
    iterations = np.zeros(b_n, dtype=np.int64)
    active = np.arange(b_n)
    for it in range(max_iterations + 1):
        if len(active) == 0:
            break
        current = base_local[active]
        if it:
            current = blend(
                current.reshape(len(current), -1), weights[active], flat_deltas
            ).reshape(current.shape)
        det = detect(current, layout, margin=margin)
        if it == 0:
            within_before[active] = det.within
        within_after[active] = det.within
        colliding = det.colliding
        c = det.constraints
        deepest = np.zeros(len(active))
        if len(c.depth):
            np.maximum.at(deepest, c.face, np.where(c.within, c.depth - margin, 0.0))
        depth_after[active] = deepest
        if it == max_iterations or not colliding.any():
            break
        jac = depth_jacobian(c, layout, deltas_local)
        order = np.argsort(c.face, kind="stable")
        bounds = np.searchsorted(c.face[order], np.arange(len(active) + 1))
        for j in np.flatnonzero(colliding):
            rows = order[bounds[j] : bounds[j + 1]]
            face = int(active[j])
            weights[face] += solve_eq5(
                jac[rows], c.depth[rows], c.kind[rows], upper=1.0 - weights[face]
            )
            iterations[face] = it + 1
        active = active[colliding]
    return CollisionSolution(weights, within_before, within_after, depth_after, iterations)
