"""Table III's intervals: the first-bin share under bootstrap weights against plain loops and
the repeatability module's bins; both readings' contrast made to return each verdict."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from emogen.analysis.repeatability import repeatability_bins
from emogen.analysis.replication.repeat_intervals import (
    BinContrast,
    BinShares,
    bin_pairs,
    close_pairs,
    first_bin_share,
)


def _faces(rng: np.random.Generator, n: int, tight: bool) -> np.ndarray:
    """Tight: small noise around one face (every pair close); else sparse random faces (CD
    near 1: no pair close)."""
    if tight:
        base = np.linspace(0.2, 1.0, 20)
        return np.clip(base + rng.normal(0, 0.03, (n, 20)), 0, None)
    faces = np.zeros((n, 20))
    for f in faces:
        f[rng.choice(20, 3, replace=False)] = rng.uniform(0.2, 1, 3)
    return faces


def _plain_share(faces: np.ndarray, group: np.ndarray, counts: np.ndarray) -> float:
    """Expand the runs by their counts; count pairs of distinct runs of one group."""
    idx = np.repeat(np.arange(len(faces)), counts.astype(int))
    close = total = 0
    for a, b in itertools.combinations(idx, 2):
        if a == b or group[a] != group[b]:
            continue
        fa, fb = faces[a], faces[b]
        cd = 1 - fa @ fb / (np.linalg.norm(fa) * np.linalg.norm(fb))
        total += 1
        close += cd < 0.25
    return close / total


def test_first_bin_share_against_the_bins_and_a_plain_loop() -> None:
    rng = np.random.default_rng(3)
    faces = np.concatenate([_faces(rng, 14, True), _faces(rng, 10, False)])
    one = np.zeros(len(faces), dtype=int)
    close, same = close_pairs(faces, one)
    share = first_bin_share(close, same, np.ones((1, len(faces))))[0]
    assert share == pytest.approx(repeatability_bins(faces)[0])
    group = rng.integers(0, 2, len(faces))
    counts = rng.multinomial(len(faces), np.full(len(faces), 1 / len(faces)))
    close, same = close_pairs(faces, group)
    got = first_bin_share(close, same, counts[None].astype(float))[0]
    assert got == pytest.approx(_plain_share(faces, group, counts))


def _rows(rng: np.random.Generator, tight: list[bool], biases: list[float]) -> list[np.ndarray]:
    n = 40
    group = np.repeat([1, 2], n // 2)
    arrays: list[np.ndarray] = [group]
    for t, b in zip(tight, biases, strict=True):
        arrays += [_faces(rng, n, t), b + rng.normal(0, 0.01, n)]
    return arrays


@pytest.mark.parametrize(
    ("kind", "sign", "tight", "biases", "verdict"),
    [
        # slope: protocol flat, fixed rises from spread to tight: protocol less sensitive
        ("slope", -1, [True, True, False, True], [0.7, 0.5, 0.9, 0.4], "holds"),
        ("slope", -1, [False, True, True, True], [0.7, 0.5, 0.9, 0.4], "differs"),
        ("slope", -1, [True, True, True, True], [0.7, 0.5, 0.9, 0.4], "differs"),  # a precise zero
        # matched: the fixed row tight where protocol (flat slope) is spread at that bias
        ("matched", +1, [False, False, False, True], [0.7, 0.5, 0.5, 0.45], "holds"),
        ("matched", +1, [True, True, True, False], [0.7, 0.5, 0.5, 0.45], "differs"),
        (
            "matched",
            +1,
            [True, True, True, True],
            [0.7, 0.5, 0.5, 0.45],
            "differs",
        ),  # a precise zero
    ],
)
def test_bin_contrast_reaches_each_verdict(
    kind: str, sign: int, tight: list[bool], biases: list[float], verdict: str
) -> None:
    arrays = _rows(np.random.default_rng(7), tight, biases)
    assert BinContrast(kind, sign, resamples=200)(*arrays).verdict == verdict


def test_matched_contrast_moves_protocol_along_its_own_slope() -> None:
    """Protocol rises 50 points over 0.2 bias (250 / unit); a fixed row 0.1 closer than the
    protocol row it is matched with is credited 25 points of that rise, no more."""
    rng = np.random.default_rng(1)
    n = 40
    group = np.ones(n, dtype=int)
    half = np.concatenate([_faces(rng, n // 2, True), _faces(rng, n // 2, False)])
    share_half = repeatability_bins(half)[0] * 100
    tight, spread = _faces(rng, n, True), _faces(rng, n, False)
    arrays = [group, spread, np.full(n, 0.7), half, np.full(n, 0.5), half, np.full(n, 0.5)]
    arrays += [tight, np.full(n, 0.4)]
    got = BinContrast("matched", +1, resamples=50)(*arrays).estimate
    share_spread, share_tight = (repeatability_bins(f)[0] * 100 for f in (spread, tight))
    slope = (share_half - share_spread) / 0.2
    assert got == pytest.approx(share_tight - (share_half + slope * 0.1))


def test_bin_contrast_refuses_bad_input() -> None:
    with pytest.raises(ValueError, match="kind must be one of"):
        BinContrast("rank", +1)
    with pytest.raises(ValueError, match="4 rows of runs"):
        BinContrast("slope", -1)(np.zeros(3), np.zeros((3, 2)), np.zeros(3))


def test_bin_pairs_give_the_repeatability_bins() -> None:
    rng = np.random.default_rng(11)
    faces = np.concatenate([_faces(rng, 15, True), _faces(rng, 15, False)])
    group = np.zeros(len(faces), dtype=int)
    bins, same = bin_pairs(faces, group)
    shares = [first_bin_share(b, same, np.ones((1, len(faces))))[0] for b in bins]
    np.testing.assert_allclose(shares, repeatability_bins(faces))


def _two(tight_a: bool, tight_b: bool) -> list[np.ndarray]:
    rng = np.random.default_rng(12)
    group = np.repeat([1, 2], 20)
    return [group, _faces(rng, 40, tight_a), _faces(rng, 40, tight_b)]


@pytest.mark.parametrize(
    ("kind", "level", "weaker", "rows", "verdict"),
    [
        ("first_at_least", 50, 0, (True,), "holds"),
        ("first_at_least", 50, 0, (False,), "differs"),
        ("first_above", 0, 0, (True, False), "holds"),
        ("first_above", 0, 0, (False, True), "differs"),
        ("first_above", 0, 0, (True, True), "differs"),  # a precise zero
        ("tvd_below", 10, 20, (True, True), "holds"),
        ("tvd_below", 10, 20, (True, False), "differs"),
        ("tvd_below", 0.5, 150, (True, False), "partly"),
    ],
)
def test_bin_shares_reach_each_verdict(
    kind: str, level: float, weaker: float, rows: tuple[bool, ...], verdict: str
) -> None:
    arrays = _two(rows[0], rows[-1])[: 1 + len(rows)]
    got = BinShares(kind, level, weaker, resamples=100)(*arrays)
    assert got.verdict == verdict, got.text()


@pytest.mark.parametrize(
    ("tight", "weaker", "verdict"),
    [(True, 20, "holds"), (False, 20, "differs"), (False, 150, "partly")],
)
def test_bin_shares_against_a_reference_row(tight: bool, weaker: float, verdict: str) -> None:
    """``tvd_to``: one row's bins against a stated row (the paper's), here a row's own bins
    computed plainly by repeatability_bins (TVD 0 up to resampling) for tight faces."""
    rng = np.random.default_rng(21)
    group = np.repeat([1, 2], 20)
    faces = _faces(rng, 40, tight)
    reference = tuple(repeatability_bins(_faces(np.random.default_rng(22), 40, True)) * 100)
    got = BinShares("tvd_to", 10, weaker, reference=reference, resamples=100)(group, faces)
    assert got.verdict == verdict, got.text()


def test_bin_shares_inconclusive_and_refusals() -> None:
    """A mixed row (half tight): its first-bin share near a level set at its own value."""
    rng = np.random.default_rng(13)
    mixed = np.concatenate([_faces(rng, 20, True), _faces(rng, 20, False)])
    group = np.ones(40, dtype=int)
    level = repeatability_bins(mixed)[0] * 100
    assert BinShares("first_at_least", level, resamples=100)(group, mixed).verdict == (
        "inconclusive"
    )
    with pytest.raises(ValueError, match="kind must be one of"):
        BinShares("median")
    with pytest.raises(ValueError, match="needs a group array and the rows"):
        BinShares("tvd_below", 10, 20)(group, mixed)
    with pytest.raises(ValueError, match="the reference needs 4 bins"):
        BinShares("tvd_to", 10, 20, reference=(50.0, 50.0))(group, mixed)
