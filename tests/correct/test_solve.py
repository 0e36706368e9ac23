"""Eq. 5: the bounded regularised least squares, cross-type rules and the alternation."""

from __future__ import annotations

import itertools

import numpy as np
from scipy.optimize import minimize

from emogen.correct.collision import LIP, TEETH
from emogen.correct.solve import W1, solve_eq5


def cost(w, a, b):  # type: ignore[no-untyped-def]
    m = len(b)
    return W1 * np.sum((a @ w - b) ** 2) + (1 - W1) * m * np.sum(w**2)


def test_single_type_matches_a_generic_bounded_minimiser() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        m = int(rng.integers(3, 40))
        a = np.zeros((m, 8))
        a[:, :4] = rng.uniform(0, 1, (m, 4))
        b = rng.uniform(0, 0.6, m)
        w = solve_eq5(a, b, np.full(m, LIP))
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


def test_weights_hit_their_bounds_when_depth_demands() -> None:
    a = np.zeros((5, 8))
    a[:, :4] = 0.25
    w = solve_eq5(a, np.full(5, 5.0), np.full(5, LIP))
    np.testing.assert_allclose(w[:4], 1.0)
    w = solve_eq5(a, np.full(5, 0.3), np.full(5, LIP), upper=np.full(8, 0.2))
    np.testing.assert_allclose(w[:4], 0.2)


def test_cross_type_coefficients_only_count_when_both_types_collide() -> None:
    # teeth correctives also separate these lip pairs a little (cross coefficients)
    a = np.zeros((4, 8))
    a[:, :4] = np.eye(4)
    a[:, 4:] = 0.5 * np.eye(4)
    b = np.full(4, 0.4)
    lip_only = solve_eq5(a, b, np.full(4, LIP))
    assert np.all(lip_only[4:] == 0)  # with no teeth collision the cross terms are disabled
    # the same lip pairs with a teeth collision: the teeth weights' contribution is a constant
    # in the lip constraints (paper's alternation), so the lip weights need less
    t = np.zeros((1, 8))
    t[0, 4:] = 1.0
    both = solve_eq5(np.vstack([a, t]), np.r_[b, 0.8], np.r_[np.full(4, LIP), TEETH])
    assert np.all(both[4:] > 0) and np.all(both[:4] < lip_only[:4])


def test_alternation_reaches_the_fixed_point() -> None:
    rng = np.random.default_rng(3)
    a = rng.uniform(0, 0.4, (12, 8))
    a[:6, :4] += 0.6
    a[6:, 4:] += 0.6
    kind = np.r_[np.full(6, LIP), np.full(6, TEETH)]
    b = rng.uniform(0.1, 0.5, 12)
    w = solve_eq5(a, b, kind)
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


def test_no_pairs_no_weights() -> None:
    w = solve_eq5(np.zeros((0, 8)), np.zeros(0), np.zeros(0, dtype=int))
    assert np.all(w == 0)
