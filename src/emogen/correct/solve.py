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

Two solvers of each block, recorded with every corrected study trial so that a recorded study
replays bit for bit (:data:`SOLVERS`): solver 1 calls ``scipy.optimize.lsq_linear`` (BVLS) on
the stacked system; solver 2 (the current one) solves the same box-constrained problem, four
weights at a time, exactly, compiled: the normal equations H w = g (H = w₁AᵀA + (1 − w₁)M I,
positive definite) are solved on each pattern of free, lower-bound and upper-bound weights,
fewest bounds first, until one satisfies the optimality (KKT) conditions — the unique
minimiser, since the cost is strictly convex. Both give the same weights up to rounding
(tested, ≤ 1e-9); solver 2 costs microseconds where BVLS costs ~0.2 ms a block, and its
arithmetic is plain loops in a fixed order (no BLAS/LAPACK: the same bits on every machine).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from emogen.correct.blend import blend
from emogen.correct.collision import (
    CONTACT_TOLERANCE,
    LIP,
    TEETH,
    CollisionLayout,
    depth_jacobian,
    detect,
    detect_faces,
)
from emogen.solvers import CURRENT_SOLVER, SOLVERS, check_solver

#: CURRENT_SOLVER, SOLVERS and check_solver live in :mod:`emogen.solvers` (no numba there).
__all__ = ["CURRENT_SOLVER", "SOLVERS", "check_solver", "solve_collisions", "solve_eq5"]

W1 = 0.98
MAX_ITERATIONS = 6
ALTERNATIONS = 8
DEPTH_MARGIN = 0.03  # cm added to every δb, so the regularised solution clears the contact
N_ZONES = 4
KKT_TOLERANCE = 1e-12  # relative to the problem's scale


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
    """Solver 1: argmin_{0 ≤ w ≤ upper} w₁‖a w − b‖² + reg ‖w‖² (reg = (1 − w₁) M).

    Kept for trials corrected with it: needed by
    tests/study/test_recorded_before.py::test_recorded_study_replays_exactly."""
    from scipy.optimize import lsq_linear

    n = a.shape[1]
    if not np.any(upper > 0):
        return np.zeros(n)
    lhs = np.vstack([np.sqrt(W1) * a, np.sqrt(reg) * np.eye(n)])
    rhs = np.concatenate([np.sqrt(W1) * b, np.zeros(n)])
    hi = np.maximum(upper, 1e-12)  # lsq_linear wants lower < upper
    return np.clip(lsq_linear(lhs, rhs, bounds=(np.zeros(n), hi), method="bvls").x, 0.0, upper)


@njit(cache=True, nogil=True)
def _box_qp(h: np.ndarray, g: np.ndarray, upper: np.ndarray) -> np.ndarray:  # pragma: no cover
    """Solver 2's block: argmin_{0 ≤ w ≤ upper} ½ wᵀ h w − gᵀ w for a small positive definite
    h (n ≤ 8), exactly: every pattern of free / at 0 / at upper weights, fewest bounds first,
    the free weights from their equations (Cholesky, plain loops), until one is feasible and
    optimal (KKT, relative tolerance ``KKT_TOLERANCE``). A weight with upper ≤ 0 stays at 0."""
    n = g.shape[0]
    scale = 1.0
    for i in range(n):
        scale = max(scale, abs(g[i]), abs(h[i, i]))
    tol = KKT_TOLERANCE * scale
    state = np.zeros(n, dtype=np.int64)  # 0 free, 1 at 0, 2 at upper
    w = np.zeros(n)
    free = np.empty(n, dtype=np.int64)
    chol = np.empty((n, n))
    rhs = np.empty(n)
    total = 3**n
    for n_bound in range(n + 1):
        for code in range(total):
            c, bound, usable = code, 0, True
            for i in range(n):
                state[i] = c % 3
                c //= 3
                bound += state[i] != 0
                if upper[i] <= 0.0 and state[i] != 1:
                    usable = False
            if bound != n_bound or not usable:
                continue
            n_free = 0
            for i in range(n):
                if state[i] == 0:
                    free[n_free] = i
                    n_free += 1
                    w[i] = 0.0
                else:
                    w[i] = 0.0 if state[i] == 1 else upper[i]
            # h_FF x = g_F − h_FB w_B (Cholesky; h_FF is positive definite)
            for r in range(n_free):
                i = free[r]
                acc = g[i]
                for j in range(n):
                    if state[j] != 0:
                        acc -= h[i, j] * w[j]
                rhs[r] = acc
            ok = True
            for r in range(n_free):
                for q in range(r + 1):
                    acc = h[free[r], free[q]]
                    for k in range(q):
                        acc -= chol[r, k] * chol[q, k]
                    if r == q:
                        if acc <= 0.0:
                            ok = False
                            break
                        chol[r, r] = np.sqrt(acc)
                    else:
                        chol[r, q] = acc / chol[q, q]
                if not ok:
                    break
            if not ok:
                continue
            for r in range(n_free):  # forward: L y = rhs
                acc = rhs[r]
                for k in range(r):
                    acc -= chol[r, k] * rhs[k]
                rhs[r] = acc / chol[r, r]
            for r in range(n_free - 1, -1, -1):  # back: Lᵀ x = y
                acc = rhs[r]
                for k in range(r + 1, n_free):
                    acc -= chol[k, r] * rhs[k]
                rhs[r] = acc / chol[r, r]
            for r in range(n_free):
                x = rhs[r]
                if x < -tol or x > upper[free[r]] + tol:
                    ok = False
                    break
                w[free[r]] = min(max(x, 0.0), upper[free[r]])
            if not ok:
                continue
            for i in range(n):  # the gradient h w − g: ≥ 0 at 0, ≤ 0 at upper
                if state[i] == 0:
                    continue
                grad = -g[i]
                for j in range(n):
                    grad += h[i, j] * w[j]
                if (state[i] == 1 and upper[i] > 0.0 and grad < -tol) or (
                    state[i] == 2 and grad > tol
                ):
                    ok = False
                    break
            if ok:
                return w
    raise ValueError("eq. 5: no pattern of bounds satisfies the optimality conditions")


@njit(cache=True, nogil=True)
def _eq5_compiled(
    a: np.ndarray, b: np.ndarray, kind: np.ndarray, ub: np.ndarray, w1: float, alternations: int
) -> np.ndarray:  # pragma: no cover - compiled
    """Solver 2: :func:`solve_eq5` (the same rules and alternation), compiled."""
    m = b.shape[0]
    w = np.zeros(2 * N_ZONES)
    if m == 0:
        return w
    reg = (1.0 - w1) * m
    has = np.zeros(2, dtype=np.bool_)
    for r in range(m):
        has[kind[r]] = True
    both = has[0] and has[1]
    h = np.empty((N_ZONES, N_ZONES))
    g = np.empty(N_ZONES)
    before = np.empty(2 * N_ZONES)
    for _ in range(alternations if both else 1):
        before[:] = w
        for k in range(2):
            if not has[k]:
                continue
            own, other = k * N_ZONES, (1 - k) * N_ZONES
            for i in range(N_ZONES):
                g[i] = 0.0
                for j in range(N_ZONES):
                    h[i, j] = reg if i == j else 0.0
            for r in range(m):
                if kind[r] != k:
                    continue
                target = b[r]
                if both:  # the other type's contribution: a constant
                    for j in range(N_ZONES):
                        target -= a[r, other + j] * w[other + j]
                for i in range(N_ZONES):
                    g[i] += w1 * a[r, own + i] * target
                    for j in range(N_ZONES):
                        h[i, j] += w1 * a[r, own + i] * a[r, own + j]
            block = _box_qp(h, g, ub[own : own + N_ZONES])
            for i in range(N_ZONES):
                w[own + i] = block[i]
        change = 0.0
        for i in range(2 * N_ZONES):
            change = max(change, abs(w[i] - before[i]))
        if change < 1e-5:
            break
    return w


@njit(cache=True, nogil=True)
def _round_compiled(
    face: np.ndarray,
    kind: np.ndarray,
    anchor: np.ndarray,
    partner: np.ndarray,
    partner_bary: np.ndarray,
    depth: np.ndarray,
    anchor_corners: np.ndarray,
    anchor_bary: np.ndarray,
    lower: np.ndarray,
    deltas: np.ndarray,
    active: np.ndarray,
    colliding: np.ndarray,
    weights: np.ndarray,
    iterations: np.ndarray,
    it: int,
    w1: float,
    alternations: int,
) -> None:  # pragma: no cover - compiled
    """Solver 2's solve round, compiled: for every colliding face of the batch, the depth
    jacobian of its pairs (eqs. 3–4, as :func:`depth_jacobian`: the anchor's corrective offset
    minus the partner's along the type's axis, signed for the negative ray) and the eq. 5
    increment (:func:`_eq5_compiled`), added to its weights (``anchor``: index in the layout's
    anchor table, lip anchors first)."""
    n_c = deltas.shape[0]
    m = face.shape[0]
    for j in range(active.shape[0]):
        if not colliding[j]:
            continue
        n_rows = 0
        for r in range(m):
            n_rows += face[r] == j
        a = np.zeros((n_rows, n_c))
        b = np.empty(n_rows)
        k = np.empty(n_rows, dtype=np.int64)
        row = 0
        for r in range(m):
            if face[r] != j:
                continue
            axis = 1 if kind[r] == 0 else 2  # lip: y, teeth: z
            sign = 1.0 if kind[r] == 0 else -1.0  # the negative ray's direction
            for c in range(n_c):
                at_anchor = 0.0
                at_partner = 0.0
                for q in range(3):
                    at_anchor += (
                        anchor_bary[anchor[r], q] * deltas[c, anchor_corners[anchor[r], q], axis]
                    )
                    at_partner += partner_bary[r, q] * deltas[c, lower[partner[r], q], axis]
                a[row, c] = sign * (at_anchor - at_partner)
            b[row] = depth[r]
            k[row] = kind[r]
            row += 1
        f = active[j]
        upper = np.empty(n_c)
        for c in range(n_c):
            upper[c] = 1.0 - weights[f, c]
        step = _eq5_compiled(a, b, k, upper, w1, alternations)
        for c in range(n_c):
            weights[f, c] += step[c]
        iterations[f] = it + 1


@njit(cache=True, nogil=True)
def _solve_compiled(
    base_local: np.ndarray,
    deltas_local: np.ndarray,
    lower: np.ndarray,
    lower_vertices: np.ndarray,
    anchor_corners: np.ndarray,
    anchor_bary: np.ndarray,
    anchor_kind: np.ndarray,
    cell: float,
    tolerance: float,
    margin: float,
    max_iterations: int,
    w1: float,
    alternations: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """Solver 2's detect–solve loop of a batch, compiled whole (:func:`_solve_stepwise` with
    solver 2, the same arithmetic in the same order, without a trip through Python per round):
    each round blends the still-colliding faces' current positions (base + the collision
    correctives at their weights so far, shape by shape, zero weights skipped, as
    :func:`emogen.correct.blend.blend`), detects (:func:`detect_faces`), records within counts
    and the deepest remaining pair, and solves the colliding faces' increments
    (:func:`_round_compiled`). Returns weights, within_before, within_after, depth_after,
    iterations (:class:`CollisionSolution`)."""
    b_n, l_n, n_c = base_local.shape[0], base_local.shape[1], deltas_local.shape[0]
    n_lip = 0
    for n in range(anchor_kind.shape[0]):
        n_lip += anchor_kind[n] == LIP
    weights = np.zeros((b_n, n_c))
    within_before = np.zeros((b_n, 2), dtype=np.int64)
    within_after = np.zeros((b_n, 2), dtype=np.int64)
    depth_after = np.zeros(b_n)
    iterations = np.zeros(b_n, dtype=np.int64)
    active = np.arange(b_n)
    for it in range(max_iterations + 1):
        n_act = active.shape[0]
        if n_act == 0:
            break
        # round 0 reads the batch as given, in place: copying it cost ~8 % of correcting a
        # dynamic population's ~160 keyframe faces (27.8 → 25.6 ms, docs/ga.md)
        current = base_local
        if it:
            current = np.empty((n_act, l_n, 3))
        for i in range(n_act if it else 0):
            f = active[i]
            current[i] = base_local[f]
            for k in range(n_c):
                w = weights[f, k]
                if w != 0.0:
                    for v in range(l_n):
                        for d in range(3):
                            current[i, v, d] += w * deltas_local[k, v, d]
        within, ids, values = detect_faces(
            current,
            lower,
            lower_vertices,
            anchor_corners,
            anchor_bary,
            anchor_kind,
            cell,
            tolerance,
        )
        colliding = np.zeros(n_act, dtype=np.bool_)
        for i in range(n_act):
            if it == 0:
                within_before[active[i]] = within[i]
            within_after[active[i]] = within[i]
            colliding[i] = within[i, 0] + within[i, 1] > 0
        m = ids.shape[0]
        face, anchor, partner = ids[:, 0].copy(), ids[:, 1].copy(), ids[:, 2].copy()
        kind = np.empty(m, dtype=np.int64)
        bary = np.empty((m, 3))
        depth = np.empty(m)
        deepest = np.zeros(n_act)
        for r in range(m):
            kind[r] = TEETH if anchor[r] >= n_lip else LIP
            u, v = values[r, 0], values[r, 1]
            bary[r, 0], bary[r, 1], bary[r, 2] = 1.0 - u - v, u, v
            depth[r] = values[r, 2] + margin
            if ids[r, 3] != 0:  # within: (δb + margin) − margin, as the stepwise loop has it
                deepest[face[r]] = max(deepest[face[r]], depth[r] - margin)
        for i in range(n_act):
            depth_after[active[i]] = deepest[i]
        if it == max_iterations or not colliding.any():
            break
        _round_compiled(
            face,
            kind,
            anchor,
            partner,
            bary,
            depth,
            anchor_corners,
            anchor_bary,
            lower,
            deltas_local,
            active,
            colliding,
            weights,
            iterations,
            it,
            w1,
            alternations,
        )
        active = active[colliding]
    return weights, within_before, within_after, depth_after, iterations


def solve_eq5(
    a: np.ndarray,
    b: np.ndarray,
    kind: np.ndarray,
    upper: np.ndarray | None = None,
    *,
    solver: int = CURRENT_SOLVER,
) -> np.ndarray:
    """Collision weights (8,) for one face from its pairs: a (M, 8) δa, b (M,) δb, kind (M,).

    Columns 0–3 are the lip correctives, 4–7 the teeth ones; ``upper`` (8,) bounds the weights
    (default 1). A type without pairs keeps its correctives at 0. ``solver``: see
    :data:`SOLVERS` and the module docstring.
    """
    ub = np.ones(2 * N_ZONES) if upper is None else np.asarray(upper, dtype=np.float64)
    if check_solver(solver) == 2:
        return _eq5_compiled(
            np.ascontiguousarray(a, dtype=np.float64),
            np.ascontiguousarray(b, dtype=np.float64),
            np.ascontiguousarray(kind, dtype=np.int64),
            np.ascontiguousarray(ub),
            W1,
            ALTERNATIONS,
        )
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
    solver: int = CURRENT_SOLVER,
) -> CollisionSolution:
    """Detect and correct collisions of a batch.

    base_local : (B, L, 3) float64 positions of ``layout.vertices`` before collision correction
    deltas_local : (8, L, 3) the collision correctives at those vertices
    solver : the eq. 5 block solver (:data:`SOLVERS`); solver 2's whole loop is compiled
      (:func:`_solve_compiled`: the same bits as :func:`_solve_stepwise`, tested)
    """
    if check_solver(solver) == 2:
        solved = _solve_compiled(
            np.ascontiguousarray(base_local, dtype=np.float64),
            np.ascontiguousarray(deltas_local, dtype=np.float64),
            layout.lower,
            layout.lower_vertices,
            *layout.anchor_table,
            layout.cell,
            CONTACT_TOLERANCE,
            margin,
            max_iterations,
            W1,
            ALTERNATIONS,
        )
        return CollisionSolution(*solved)
    return _solve_stepwise(
        base_local,
        deltas_local,
        layout,
        max_iterations=max_iterations,
        margin=margin,
        solver=solver,
    )


def _solve_stepwise(
    base_local: np.ndarray,
    deltas_local: np.ndarray,
    layout: CollisionLayout,
    *,
    max_iterations: int,
    margin: float,
    solver: int,
) -> CollisionSolution:
    """The detect–solve loop round by round in Python (solver 1, whose BVLS solves run in
    scipy; and, for the tests, solver 2 as the compiled loop's reference)."""
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
        if solver == 2:
            _round_compiled(
                c.face,
                c.kind,
                c.anchor + len(layout.anchors[LIP]) * c.kind,
                c.partner,
                c.partner_bary,
                c.depth,
                *layout.anchor_table[:2],
                layout.lower,
                deltas_local,
                active,
                colliding,
                weights,
                iterations,
                it,
                W1,
                ALTERNATIONS,
            )
            active = active[colliding]
            continue
        jac = depth_jacobian(c, layout, deltas_local)
        order = np.argsort(c.face, kind="stable")
        bounds = np.searchsorted(c.face[order], np.arange(len(active) + 1))
        for j in np.flatnonzero(colliding):
            rows = order[bounds[j] : bounds[j + 1]]
            face = int(active[j])
            weights[face] += solve_eq5(
                jac[rows], c.depth[rows], c.kind[rows], upper=1.0 - weights[face], solver=solver
            )
            iterations[face] = it + 1
        active = active[colliding]
    return CollisionSolution(weights, within_before, within_after, depth_after, iterations)
