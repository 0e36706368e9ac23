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
