"""Permutation tests with the participant as the unit, for many outcomes at once, with max-T
family-wise control (Westfall & Young 1993) beside Benjamini–Hochberg FDR (1995).

* :func:`paired_signflip`: paired contrasts (one participant's difference between two of their
  own conditions): under H0 the two conditions are exchangeable within the participant, so the
  sign of each participant's difference vector is a fair coin. One flip per participant is
  shared by all outcomes of a contrast (their dependence is kept); contrasts are flipped
  independently of one another (exact per contrast; across contrasts the max is stochastically
  larger than under the real dependence — Šidák / the Gaussian correlation inequality — so the
  family-wise control is conservative, never liberal).
* :func:`group_permutation`: two groups of participants: under H0 the group labels are
  exchangeable over participants; one relabelling of participants is shared by all outcomes.
  The statistic is Welch's t (a studentised permutation test stays valid when the groups'
  variances differ: Janssen 1997; Chung & Romano 2013).

The statistic is the studentised mean difference (the t statistic), whose p-value comes from the
permutation distribution, never from the t distribution (bounded, zero-inflated weights are far
from normal). p-values are ``(1 + #{T* ≥ |T|}) / (1 + B)`` (Phipson & Smyth 2010); with few
enough participants every relabelling is enumerated instead (exact p-values).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

#: Chunk of permutations evaluated at once (bounds memory).
CHUNK = 500


@dataclass(frozen=True)
class PermutationResult:
    """Per contrast × outcome (C, G): the statistic, its permutation p, its max-T adjusted p
    (family: every contrast × outcome), its BH q; and the number of relabellings used."""

    t: np.ndarray
    p: np.ndarray
    p_maxt: np.ndarray
    q_bh: np.ndarray
    permutations: int
    exact: bool


def _paired_t(total: np.ndarray, squares: np.ndarray, n: int) -> np.ndarray:
    """One-sample t of differences from their sum and sum of squares (0 where no spread)."""
    mean = total / n
    var = np.maximum(squares / n - mean**2, 0.0) * n / (n - 1)
    se = np.sqrt(var / n)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(se > 1e-12, mean / np.where(se > 1e-12, se, 1.0), 0.0)


def _finish(t: np.ndarray, null_abs: list[np.ndarray], exact: bool) -> PermutationResult:
    """p, max-T p and BH q from |T| and the chunks of permuted |T*| (B, C, G)."""
    null = np.concatenate(null_abs, axis=0)
    b = null.shape[0]
    obs = np.abs(t) - 1e-12 * np.maximum(1.0, np.abs(t))  # ties count as extreme
    raw = (null >= obs[None]).sum(axis=0)
    top = null.reshape(b, -1).max(axis=1)
    over = (top[:, None] >= obs.reshape(1, -1)).sum(axis=0).reshape(t.shape)
    add = 0 if exact else 1
    p = (raw + add) / (b + add)
    p_maxt = (over + add) / (b + add)
    q = stats.false_discovery_control(p.ravel(), method="bh").reshape(p.shape)
    return PermutationResult(t, p, p_maxt, q, b, exact)


def paired_signflip(
    d: np.ndarray, *, permutations: int, rng: np.random.Generator
) -> PermutationResult:
    """Sign-flip test of ``d`` (n participants, C contrasts, G outcomes) against zero mean.

    Exact (all 2^n flips) when there is one contrast and 2^n ≤ ``permutations``."""
    n, c, _ = d.shape
    sq = (d**2).sum(axis=0)
    t = _paired_t(d.sum(axis=0), sq, n)
    exact = c == 1 and 2**n <= permutations
    chunks: list[np.ndarray] = []
    if exact:
        signs = np.array(list(itertools.product((1.0, -1.0), repeat=n)))  # (2^n, n)
        for s in np.array_split(signs, max(1, len(signs) // CHUNK)):
            chunks.append(np.abs(_paired_t(np.einsum("bn,ncg->bcg", s, d), sq, n)))
    else:
        left = permutations
        while left > 0:
            k = min(CHUNK, left)
            s = rng.choice((-1.0, 1.0), size=(k, n, c))
            chunks.append(np.abs(_paired_t(np.einsum("bnc,ncg->bcg", s, d), sq, n)))
            left -= k
    return _finish(t, chunks, exact)


def _welch(x: np.ndarray, member: np.ndarray) -> np.ndarray:
    """Welch t (group 1 − group 0) of x (n, K) for each labelling ``member`` (B, n) of 0/1."""
    m = member.astype(np.float64)
    n1 = m.sum(axis=1, keepdims=True)
    n0 = m.shape[1] - n1
    s1, s0 = m @ x, (1 - m) @ x
    q1, q0 = m @ x**2, (1 - m) @ x**2
    mean1, mean0 = s1 / n1, s0 / n0
    v1 = np.maximum(q1 - n1 * mean1**2, 0.0) / (n1 - 1)
    v0 = np.maximum(q0 - n0 * mean0**2, 0.0) / (n0 - 1)
    se = np.sqrt(v1 / n1 + v0 / n0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(se > 1e-12, (mean1 - mean0) / np.where(se > 1e-12, se, 1.0), 0.0)


def group_permutation(
    x: np.ndarray, member: np.ndarray, *, permutations: int, rng: np.random.Generator
) -> PermutationResult:
    """Welch-t permutation test of group 1 vs group 0 (``member``: (n,) bool) on ``x``
    (n participants, C contrasts, G outcomes), one relabelling shared by all outcomes.

    Exact (every split of the participants into groups of the observed sizes) when their number
    is ≤ ``permutations``."""
    n, c, g = x.shape
    member = np.asarray(member, dtype=bool)
    n1 = int(member.sum())
    if n1 < 2 or n - n1 < 2:
        raise ValueError(f"each group needs >= 2 participants; got {n1} and {n - n1}")
    flat = x.reshape(n, c * g)
    t = _welch(flat, member[None]).reshape(c, g)
    splits, exact = relabellings(member, permutations=permutations, rng=rng)
    chunks = [
        np.abs(_welch(flat, s)).reshape(len(s), c, g)
        for s in np.array_split(splits, max(1, len(splits) // CHUNK))
    ]
    return _finish(t, chunks, exact)


def relabellings(
    member: np.ndarray, *, permutations: int, rng: np.random.Generator
) -> tuple[np.ndarray, bool]:
    """(B, n) bool relabellings of participants into groups of ``member``'s sizes: every split
    (exact, True) when there are ≤ ``permutations``, else ``permutations`` random ones."""
    n, n1 = len(member), int(np.sum(member))
    if math.comb(n, n1) <= permutations:
        splits = np.zeros((math.comb(n, n1), n), dtype=bool)
        for row, chosen in enumerate(itertools.combinations(range(n), n1)):
            splits[row, list(chosen)] = True
        return splits, True
    return np.array([rng.permutation(member) for _ in range(permutations)]), False


def shift_interval(
    x: np.ndarray, member: np.ndarray, *, level: float, permutations: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """The difference mean(group 1) − mean(group 0) over axis 0 of ``x``, with the interval
    that inverts the permutation test of a shift: δ is inside when relabelling participants of
    x − δ·member gives p > 1 − ``level`` for the difference of means (exact coverage when the
    groups differ by a shift; Lehmann 1963). One set of relabellings
    (:func:`relabellings`) serves every δ and every outcome: relabelling r moves the difference
    to A_r − δ·w_r (w_r = the share of group 1 kept in group 1 minus group 1's share of group 0,
    1 for the identity), so r counts as extreme on the δ where (A_r − δ w_r)² ≥ (D − δ)², one
    interval around D; the bounds are order statistics of those intervals' ends. Where the
    design has too few relabellings for a finite bound the bound is ±inf."""
    member = np.asarray(member, dtype=bool)
    splits, exact = relabellings(member, permutations=permutations, rng=rng)
    return _shift_bounds(x, member, splits, exact, level)


def _shift_bounds(
    x: np.ndarray, member: np.ndarray, splits: np.ndarray, exact: bool, level: float
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`shift_interval` for given relabellings ``splits`` (B, n)."""
    n = x.shape[0]
    flat = x.reshape(n, -1).astype(np.float64)
    n1 = int(member.sum())
    s = splits.astype(np.float64)
    a = s @ flat / n1 - (1 - s) @ flat / (n - n1)  # (B, F)
    kept = s @ member.astype(np.float64)
    w = (kept / n1 - (n1 - kept) / (n - n1))[:, None]
    d = flat[member].mean(axis=0) - flat[~member].mean(axis=0)
    lo, hi = _inverted(a, w, d, exact, level)
    return lo.reshape(x.shape[1:]), hi.reshape(x.shape[1:])


def signflip_interval(
    d: np.ndarray, *, level: float, permutations: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """The mean over participants (axis 0) of paired differences ``d`` with the interval that
    inverts the sign-flip test of d − δ (exact when the differences are symmetric about δ):
    flips s move the mean to mean(s·d) − δ·mean(s), so the bounds follow as in
    :func:`shift_interval`. Every flip (exact) when 2^n ≤ ``permutations``."""
    n = d.shape[0]
    flat = d.reshape(n, -1).astype(np.float64)
    exact = 2**n <= permutations
    if exact:
        signs = np.array(list(itertools.product((1.0, -1.0), repeat=n)))
    else:
        signs = rng.choice((-1.0, 1.0), size=(permutations, n))
    lo, hi = _inverted(
        signs @ flat / n, signs.mean(axis=1)[:, None], flat.mean(axis=0), exact, level
    )
    return lo.reshape(d.shape[1:]), hi.reshape(d.shape[1:])


def _inverted(
    a: np.ndarray, w: np.ndarray, d: np.ndarray, exact: bool, level: float
) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of {δ: p(δ) > 1 − level} where rearrangement r (B of them) gives the statistic
    a_r − δ w_r against the observed d − δ (see :func:`shift_interval`)."""
    always = np.abs(np.abs(w) - 1) < 1e-12  # the identity (and the swap of equal groups)
    always = np.broadcast_to(always, a.shape)
    quad = np.where(always, -1.0, w**2 - 1)
    half = a * w - d
    root = np.sqrt(np.maximum(half**2 - quad * (a**2 - d**2), 0.0))
    low = np.where(always, -np.inf, (half + root) / quad)
    high = np.where(always, np.inf, (half - root) / quad)
    b = len(a)
    extra = 0 if exact else 1
    need = math.floor(round((1 - level) * (b + extra) - extra, 9)) + 1
    need = min(max(need, 1), b)
    return np.sort(low, axis=0)[need - 1], np.sort(high, axis=0)[b - need]


def t_mean_ci(d: np.ndarray, *, level: float) -> tuple[np.ndarray, np.ndarray]:
    """Student-t CI of the mean over participants (axis 0) of ``d``: mean ± t(n − 1)·s/√n.
    (The percentile bootstrap it replaced covered 90.5% at 8 participants: it has no t
    quantile and its spread is s·√((n − 1)/n); ``benchmarks/coverage_intervals.py``.)"""
    n = d.shape[0]
    half = stats.t.ppf((1 + level) / 2, n - 1) * d.std(axis=0, ddof=1) / np.sqrt(n)
    mean = d.mean(axis=0)
    return mean - half, mean + half


def welch_difference_ci(
    x: np.ndarray, member: np.ndarray, *, level: float
) -> tuple[np.ndarray, np.ndarray]:
    """Welch CI of mean(group 1) − mean(group 0) over axis 0 of ``x``: the difference ± t(ν)
    · SE with Welch–Satterthwaite ν (unequal variances; a gene that nobody in either group
    uses has SE 0 and the point interval [0, 0])."""
    a, b = x[member], x[~member]
    va, vb = a.var(axis=0, ddof=1) / len(a), b.var(axis=0, ddof=1) / len(b)
    se2 = va + vb
    with np.errstate(invalid="ignore", divide="ignore"):
        nu = se2**2 / (va**2 / (len(a) - 1) + vb**2 / (len(b) - 1))
    nu = np.where(np.isfinite(nu), nu, len(a) + len(b) - 2)
    half = stats.t.ppf((1 + level) / 2, nu) * np.sqrt(se2)
    diff = a.mean(axis=0) - b.mean(axis=0)
    return diff - half, diff + half
