"""Cosine distance (eq. 12), batched, against scipy."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.distance import cosine

from emogen.errors import ShapeError
from emogen.metrics import cosine_distance


@settings(max_examples=80, deadline=None)
@given(
    data=st.data(),
    n=st.integers(1, 6),
    k=st.integers(1, 60),
)
def test_matches_scipy_and_stays_in_range(data, n, k) -> None:
    elems = st.floats(-1, 1, allow_nan=False).filter(lambda v: v == 0 or abs(v) > 1e-6)
    a = data.draw(arrays(np.float64, (n, k), elements=elems))
    b = data.draw(arrays(np.float64, (n, k), elements=elems))
    cd = cosine_distance(a, b)
    assert cd.shape == (n,)
    assert np.all((cd >= 0) & (cd <= 2))
    for i in range(n):
        if np.any(a[i]) and np.any(b[i]):
            assert cd[i] == pytest.approx(cosine(a[i], b[i]), abs=1e-9)


def test_blendshape_vectors_and_broadcasting() -> None:
    rng = np.random.default_rng(0)
    w = rng.random((5, 57))
    t = rng.random(57)
    np.testing.assert_allclose(cosine_distance(w, t), [cosine(x, t) for x in w], atol=1e-12)
    assert cosine_distance(w[0], t).shape == ()
    # agnostic to intensity (Figure 7)
    np.testing.assert_allclose(cosine_distance(0.3 * t, t), 0.0, atol=1e-12)


def test_zero_vector_conventions() -> None:
    z, v = np.zeros(4), np.array([0.0, 1.0, 0.0, 0.0])
    assert cosine_distance(z, v) == 1.0
    assert cosine_distance(v, z) == 1.0
    assert cosine_distance(z, z) == 0.0
    with pytest.raises(ShapeError, match="equal length"):
        cosine_distance(np.zeros(3), np.zeros(4))


# ---- ED (eq. 11) ------------------------------------------------------------------------------
from scipy.spatial.distance import euclidean, mahalanobis, seuclidean  # noqa: E402

from emogen.errors import ConfigError  # noqa: E402
from emogen.metrics import (  # noqa: E402
    PCASpace,
    VertexMahalanobis,
    VertexRMS,
    euclidean_distance,
    gene_euclidean_distance,
    vertex_rms,
)


def test_euclidean_matches_scipy() -> None:
    rng = np.random.default_rng(1)
    a, b = rng.random((7, 30)), rng.random((7, 30))
    np.testing.assert_allclose(
        euclidean_distance(a, b), [euclidean(x, y) for x, y in zip(a, b, strict=True)]
    )
    np.testing.assert_allclose(euclidean_distance(a, b[0]), [euclidean(x, b[0]) for x in a])
    assert euclidean_distance(a[0], a[0]) == 0.0
    with pytest.raises(ShapeError, match="equal length"):
        euclidean_distance(a, b[:, :3])


def test_gene_ed_compares_unique_core_genes(ict_model) -> None:
    rig = ict_model.rig
    rng = np.random.default_rng(2)
    genes = rng.random((5, len(rig.gene_names())))
    w = rig.expand(genes)
    ref = [euclidean(x, y) for x, y in zip(genes, genes[::-1], strict=True)]
    np.testing.assert_allclose(gene_euclidean_distance(rig, w, w[::-1]), ref, atol=1e-12)
    # a pair counts once: jawOpen (one shape) and mouthSmile (two shapes) weigh the same
    jaw = rig.weights_from_names({"jawOpen": 0.5})
    smile = rig.weights_from_names({"mouthSmile": 0.5})
    zero = np.zeros_like(jaw)
    assert gene_euclidean_distance(rig, jaw, zero) == pytest.approx(0.5)
    assert gene_euclidean_distance(rig, smile, zero) == pytest.approx(0.5)
    # without eye motion, eye genes do not count
    blink = rig.weights_from_names({"eyeBlink": 1.0})
    assert gene_euclidean_distance(rig, blink, zero, eye_motion=False) == 0.0


# ---- vertex RMS (eq. 13) --------------------------------------------------------------------------
def plain_rms(v1: np.ndarray, v2: np.ndarray) -> float:
    """Eq. 13 literally: a loop over the vertices."""
    total = 0.0
    for p, q in zip(v1.tolist(), v2.tolist(), strict=True):
        total += (p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 + (p[2] - q[2]) ** 2
    return float(np.sqrt(total / len(v1)))


def test_vertex_rms_matches_a_plain_loop_on_the_real_model(ict_model) -> None:
    rig = ict_model.rig
    rng = np.random.default_rng(3)
    genes = rng.random((4, len(rig.gene_names()))) * (rng.random((4, 30)) < 0.4)
    genes[0, rig.gene_index("eyeLookLeft")] = 0.9  # a strong gaze: the eyeballs rotate
    genes[1, rig.gene_index("eyeLookUp")] = 0.7
    w = rig.expand(genes)
    a, b = w[[0, 1, 2]], w[[3, 0, 0]]
    verts = ict_model.evaluate(w).astype(np.float64)
    ref = [plain_rms(verts[i], verts[j]) for i, j in ((0, 3), (1, 0), (2, 0))]
    fast = VertexRMS(ict_model)
    np.testing.assert_allclose(fast(a, b), ref, rtol=1e-5)
    np.testing.assert_allclose(vertex_rms(verts[[0, 1, 2]], verts[[3, 0, 0]]), ref, rtol=1e-9)
    # without gaze, the eyeballs only blend (as evaluate(gaze=False))
    flat = ict_model.evaluate(w, gaze=False).astype(np.float64)
    no_gaze = VertexRMS(ict_model, gaze=False)
    np.testing.assert_allclose(
        no_gaze(a, b), vertex_rms(flat[[0, 1, 2]], flat[[3, 0, 0]]), rtol=1e-5
    )
    assert not np.isclose(no_gaze(w[0], w[3]), fast(w[0], w[3]))  # the gaze matters
    # one target for many faces; a face against itself; the neutral
    np.testing.assert_allclose(fast(w, w[2]), vertex_rms(verts, verts[2]), rtol=1e-5, atol=1e-6)
    assert fast(w[1], w[1]) == pytest.approx(0.0, abs=1e-6)
    neutral = np.zeros(ict_model.n_shapes)
    assert fast(w[2], neutral) == pytest.approx(
        plain_rms(verts[2], ict_model.neutral.astype(np.float64)), rel=1e-5
    )
    with pytest.raises(ShapeError, match="VertexRMS needs weights"):
        fast(w[:, :5], w[:, :5])


def test_vertex_rms_on_the_tiny_model_is_symmetric(tiny_model) -> None:
    rng = np.random.default_rng(4)
    w = rng.random((6, tiny_model.n_shapes))
    d = VertexRMS(tiny_model)
    np.testing.assert_allclose(d(w, w[::-1]), d(w[::-1], w), rtol=1e-12)
    v = tiny_model.evaluate(w).astype(np.float64)
    np.testing.assert_allclose(d(w, w[0]), [plain_rms(x, v[0]) for x in v], rtol=1e-5, atol=1e-7)


# ---- empirical metrics (eqs. 14–16) ---------------------------------------------------------------
def synthetic_training(n: int = 40, s: int = 6, seed: int = 5) -> np.ndarray:
    rng = np.random.default_rng(seed)
    mix = rng.normal(size=(s, s)) * np.array([3, 2, 1, 0.5, 0.2, 0.05])[:, None]
    return rng.normal(size=(n, s)) @ mix + 0.5


def test_pca_ed_and_std_ed_match_scipy() -> None:
    train = synthetic_training()
    space = PCASpace.fit(train, variance=0.99)
    assert 1 <= space.n_components < train.shape[1]
    assert space.variances.sum() / train.var(0, ddof=1).sum() >= 0.99
    rng = np.random.default_rng(6)
    a, b = rng.normal(size=(5, 6)), rng.normal(size=(5, 6))
    ba, bb = space.transform(a), space.transform(b)
    np.testing.assert_allclose(
        space.ed(a, b), [euclidean(x, y) for x, y in zip(ba, bb, strict=True)]
    )
    std = [seuclidean(x, y, space.variances) for x, y in zip(ba, bb, strict=True)]
    np.testing.assert_allclose(space.std_ed(a, b), std)
    # eq. 14 = eq. 15: Mahalanobis with the training covariance of β is the standardised ED
    vi = np.linalg.inv(np.cov(space.transform(train), rowvar=False))
    np.testing.assert_allclose(
        space.std_ed(a, b), [mahalanobis(x, y, vi) for x, y in zip(ba, bb, strict=True)]
    )
    # every component: PCA ED is plain ED (a rotation)
    full = PCASpace.fit(train, variance=1.0)
    np.testing.assert_allclose(full.ed(a, b), euclidean_distance(a, b))
    with pytest.raises(ConfigError, match="at least 2 faces"):
        PCASpace.fit(train[:1])
    with pytest.raises(ConfigError, match="variance must be in"):
        PCASpace.fit(train, variance=1.5)
    with pytest.raises(ConfigError, match="do not vary"):
        PCASpace.fit(np.ones((5, 6)))


@pytest.mark.parametrize("variance", [1.0, 0.9])
def test_vertex_mahalanobis_matches_scipy_with_the_explicit_covariance(variance) -> None:
    """Small enough to form the 3N × 3N covariance: the low-rank computation must agree."""
    rng = np.random.default_rng(7)
    s, n_vertices = 6, 7
    deltas = rng.normal(size=(s, n_vertices, 3))
    train = synthetic_training(n=30, s=s)
    md = VertexMahalanobis.fit(deltas, train, variance=variance, ridge=0.5)
    flat = deltas.reshape(s, -1)
    x = train @ flat  # the training offsets δV (30, 21)
    cov = np.cov(x, rowvar=False)
    lam, vec = np.linalg.eigh(cov)
    lam, vec = lam[::-1], vec[:, ::-1]
    k = md.n_components
    ridge = 0.5 * np.trace(cov) / flat.shape[1]
    assert md.ridge_variance == pytest.approx(ridge)
    np.testing.assert_allclose(md.variances, lam[:k], rtol=1e-9)
    s_reg = (vec[:, :k] * lam[:k]) @ vec[:, :k].T + ridge * np.eye(flat.shape[1])
    if variance == 1.0:  # all components kept: S + λI
        np.testing.assert_allclose(s_reg, cov + ridge * np.eye(flat.shape[1]), atol=1e-9)
    vi = np.linalg.inv(s_reg)
    a, b = rng.random((4, s)), rng.random((4, s))
    ref = [mahalanobis(p, q, vi) for p, q in zip(a @ flat, b @ flat, strict=True)]
    np.testing.assert_allclose(md(a, b), ref, rtol=1e-7)
    assert md(a[0], a[0]) == 0.0
    with pytest.raises(ConfigError, match="ridge must be > 0"):
        VertexMahalanobis.fit(deltas, train, ridge=0)


def test_vertex_mahalanobis_on_the_real_model_stays_low_rank(ict_model) -> None:
    rig = ict_model.rig
    rng = np.random.default_rng(8)
    train = rig.expand(rng.random((200, len(rig.gene_names()))) * (rng.random((200, 30)) < 0.3))
    md = VertexMahalanobis.from_model(ict_model, train)
    assert md.coords.shape[0] == ict_model.n_shapes and md.coords.shape[1] <= ict_model.n_shapes
    d = md(train[:5], train[5:10])
    assert d.shape == (5,) and np.all(np.isfinite(d)) and np.all(d > 0)
    np.testing.assert_allclose(md(train[:5], train[5:10]), md(train[5:10], train[:5]))
