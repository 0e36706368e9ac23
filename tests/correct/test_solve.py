"""Eq. 5: the bounded regularised least squares, cross-type rules and the alternation."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import lsq_linear, minimize

from emogen.correct.collision import LIP, TEETH
from emogen.correct.solve import SOLVERS, W1, _box_qp, check_solver, solve_eq5

ALL_SOLVERS = pytest.mark.parametrize("solver", sorted(SOLVERS))


def cost(w, a, b):  # type: ignore[no-untyped-def]
    m = len(b)
    return W1 * np.sum((a @ w - b) ** 2) + (1 - W1) * m * np.sum(w**2)


@ALL_SOLVERS
def test_single_type_matches_a_generic_bounded_minimiser(solver: int) -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        m = int(rng.integers(3, 40))
        a = np.zeros((m, 8))
        a[:, :4] = rng.uniform(0, 1, (m, 4))
        b = rng.uniform(0, 0.6, m)
        w = solve_eq5(a, b, np.full(m, LIP), solver=solver)
        assert np.all(w[4:] == 0)  # no teeth pairs: teeth correctives stay off
        ref = minimize(
            cost,
            np.full(8, 0.5),
            args=(a, b),
            bounds=[(0, 1)] * 4 + [(0, 0)] * 4,
            method="L-BFGS-B",
            options={"ftol": 1e-15, "gtol": 1e-12},
        )
        assert cost(w, a, b) <= ref.fun + 1e-9
        assert np.all((w >= 0) & (w <= 1))


@ALL_SOLVERS
def test_weights_hit_their_bounds_when_depth_demands(solver: int) -> None:
    a = np.zeros((5, 8))
    a[:, :4] = 0.25
    w = solve_eq5(a, np.full(5, 5.0), np.full(5, LIP), solver=solver)
    np.testing.assert_allclose(w[:4], 1.0)
    w = solve_eq5(a, np.full(5, 0.3), np.full(5, LIP), upper=np.full(8, 0.2), solver=solver)
    np.testing.assert_allclose(w[:4], 0.2)


@ALL_SOLVERS
def test_cross_type_coefficients_only_count_when_both_types_collide(solver: int) -> None:
    # teeth correctives also separate these lip pairs a little (cross coefficients)
    a = np.zeros((4, 8))
    a[:, :4] = np.eye(4)
    a[:, 4:] = 0.5 * np.eye(4)
    b = np.full(4, 0.4)
    lip_only = solve_eq5(a, b, np.full(4, LIP), solver=solver)
    assert np.all(lip_only[4:] == 0)  # with no teeth collision the cross terms are disabled
    # the same lip pairs with a teeth collision: the teeth weights' contribution is a constant
    # in the lip constraints (paper's alternation), so the lip weights need less
    t = np.zeros((1, 8))
    t[0, 4:] = 1.0
    both = solve_eq5(np.vstack([a, t]), np.r_[b, 0.8], np.r_[np.full(4, LIP), TEETH], solver=solver)
    assert np.all(both[4:] > 0) and np.all(both[:4] < lip_only[:4])


@ALL_SOLVERS
def test_alternation_reaches_the_fixed_point(solver: int) -> None:
    rng = np.random.default_rng(3)
    a = rng.uniform(0, 0.4, (12, 8))
    a[:6, :4] += 0.6
    a[6:, 4:] += 0.6
    kind = np.r_[np.full(6, LIP), np.full(6, TEETH)]
    b = rng.uniform(0.1, 0.5, 12)
    w = solve_eq5(a, b, kind, solver=solver)
    # at the fixed point each type's weights solve their own block given the other's
    m = len(b)
    for k, own, other in ((LIP, slice(0, 4), slice(4, 8)), (TEETH, slice(4, 8), slice(0, 4))):
        rows = kind == k
        rhs = b[rows] - a[rows][:, other] @ w[other]
        best = min(
            W1 * np.sum((a[rows][:, own] @ np.array(g) - rhs) ** 2)
            + (1 - W1) * m * np.sum(np.array(g) ** 2)
            for g in itertools.product(np.linspace(0, 1, 11), repeat=4)
        )
        got = W1 * np.sum((a[rows][:, own] @ w[own] - rhs) ** 2) + (1 - W1) * m * np.sum(
            w[own] ** 2
        )
        assert got <= best + 1e-9


@ALL_SOLVERS
def test_no_pairs_no_weights(solver: int) -> None:
    w = solve_eq5(np.zeros((0, 8)), np.zeros(0), np.zeros(0, dtype=int), solver=solver)
    assert np.all(w == 0)


def _block_cost(w, a, b, reg):  # type: ignore[no-untyped-def]
    return W1 * np.sum((a @ w - b) ** 2) + reg * np.sum(w**2)


@settings(max_examples=300, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    m=st.integers(1, 30),
    zero_bounds=st.integers(0, 3),
)
def test_solver_2_block_is_the_exact_bounded_minimiser(seed: int, m: int, zero_bounds: int) -> None:
    """Solver 2's block against the KKT conditions checked here in numpy, and never worse
    than scipy's bounded least squares (TRF, an independent method) on the same problem —
    upper bounds of 0 included (a weight already at 1 in an earlier round)."""
    rng = np.random.default_rng(seed)
    a = rng.uniform(0, 1, (m, 4)) * (rng.random((m, 4)) < 0.7)
    b = rng.uniform(0, 2.0, m)
    upper = rng.uniform(0.05, 1, 4)
    upper[rng.permutation(4)[:zero_bounds]] = 0.0
    reg = (1 - W1) * m
    h = W1 * a.T @ a + reg * np.eye(4)
    g = W1 * a.T @ b
    w = _box_qp(h, g, upper)
    assert np.all((w >= 0) & (w <= upper))
    grad = h @ w - g
    scale = max(1.0, np.abs(g).max(), np.abs(np.diag(h)).max())
    free = (w > 1e-12) & (w < upper - 1e-12)
    np.testing.assert_allclose(grad[free], 0.0, atol=1e-9 * scale)
    assert np.all(grad[(w <= 1e-12) & (upper > 0)] >= -1e-9 * scale)
    assert np.all(grad[(w >= upper - 1e-12) & (upper > 0)] <= 1e-9 * scale)
    lo = np.zeros(4)
    hi = np.maximum(upper, 1e-15)
    lhs = np.vstack([np.sqrt(W1) * a, np.sqrt(reg) * np.eye(4)])
    rhs = np.r_[np.sqrt(W1) * b, np.zeros(4)]
    ref = np.clip(lsq_linear(lhs, rhs, bounds=(lo, hi), method="trf", tol=1e-14).x, 0, upper)
    assert _block_cost(w, a, b, reg) <= _block_cost(ref, a, b, reg) + 1e-9


def test_solvers_agree_where_the_bounds_are_open() -> None:
    """Solvers 1 and 2 solve the same problem: with every upper bound above 0 they give the
    same weights up to rounding (both types, the alternation included)."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        m = int(rng.integers(1, 30))
        a = rng.uniform(0, 1, (m, 8)) * (rng.random((m, 8)) < 0.7)
        kind = rng.integers(0, 2, m)
        b = rng.uniform(0, 1.5, m)
        upper = rng.uniform(0.05, 1, 8)
        w1 = solve_eq5(a, b, kind, upper, solver=1)
        w2 = solve_eq5(a, b, kind, upper, solver=2)
        np.testing.assert_allclose(w2, w1, atol=1e-9)


def test_an_unknown_solver_is_named() -> None:
    with pytest.raises(ValueError, match="collision solver must be one of \\[1, 2\\]; got 3"):
        check_solver(3)
    with pytest.raises(ValueError, match="got True"):
        solve_eq5(np.zeros((0, 8)), np.zeros(0), np.zeros(0, dtype=int), solver=True)
