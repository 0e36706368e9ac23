"""Fig. 9's mean-face tests: bootstrap over runs, each kind made to return each verdict, the
estimate against the geometry computed directly on the plain means."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.replication.geometry import FaceGeometry
from emogen.analysis.replication.mean_faces import MeanFaceTest


@pytest.fixture(scope="module")
def geometry(ict_model) -> FaceGeometry:
    return FaceGeometry(ict_model)


def _runs(model, named: dict[str, float], sd: float, seed: int, n: int = 40) -> np.ndarray:
    w = np.asarray(model.rig.weights_from_names(named), dtype=np.float64)
    noise = np.random.default_rng(seed).normal(0, sd, (n, len(w))) * (w > 0)
    return np.clip(w + noise, 0, 1)


TARGET = {"jawOpen": 0.8, "noseSneer": 0.48}


@pytest.mark.parametrize(
    ("kind", "sign", "level", "a", "b", "verdict"),
    [
        # rms: a's mean face further from the target than b's
        ("rms", +1, 0.0, {"jawOpen": 0.3, "noseSneer": 0.48}, TARGET, "holds"),
        ("rms", -1, 0.0, {"jawOpen": 0.3, "noseSneer": 0.48}, TARGET, "differs"),
        ("rms", +1, 0.0, TARGET, TARGET, "inconclusive"),
        ("rms_below", +1, 0.6, TARGET, TARGET, "holds"),
        ("rms_below", +1, 0.01, {"jawOpen": 0.3, "noseSneer": 0.48}, TARGET, "differs"),
        # ratio noseSneer/jawOpen: 0.6 in the target, 0.2 in a
        ("ratio", -1, 0.0, {"jawOpen": 0.8, "noseSneer": 0.16}, TARGET, "holds"),
        ("ratio_gap", -1, 0.6, TARGET, {"jawOpen": 0.8, "noseSneer": 0.16}, "holds"),
        ("ratio_gap", -1, 0.6, {"jawOpen": 0.8, "noseSneer": 0.16}, TARGET, "differs"),
        ("jaw", +1, 0.0, {"jawOpen": 0.3, "noseSneer": 0.48}, TARGET, "holds"),
    ],
)
def test_mean_face_test_reaches_each_verdict(
    ict_model, geometry, kind, sign, level, a, b, verdict
) -> None:
    fa, fb = _runs(ict_model, a, 0.05, 1), _runs(ict_model, b, 0.05, 2)
    target = np.broadcast_to(ict_model.rig.weights_from_names(TARGET), fa.shape)
    test = MeanFaceTest(kind, sign, level, resamples=60, geometry=geometry)
    got = test(fa, fb, target)
    assert got.verdict == verdict, got.text()
    if kind == "rms":
        plain = geometry.rms_cm(fa.mean(0), target[0]) - geometry.rms_cm(fb.mean(0), target[0])
        assert got.estimate == pytest.approx(plain)


def test_mean_face_test_refuses_bad_input(ict_model, geometry) -> None:
    with pytest.raises(ValueError, match="kind must be one of"):
        MeanFaceTest("median")
    fa = _runs(ict_model, TARGET, 0.05, 1)
    moving = fa.copy()
    with pytest.raises(ValueError, match="one target for every run"):
        MeanFaceTest("rms", geometry=geometry)(fa, fa, moving)
    with pytest.raises(ValueError, match="needs the face geometry"):
        MeanFaceTest("rms")(fa, fa, np.broadcast_to(fa[0], fa.shape))
