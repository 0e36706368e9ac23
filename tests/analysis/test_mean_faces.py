"""Fig. 9's mean-face tests: bootstrap over runs, each kind made to return each verdict, the
estimate against the geometry computed directly on the plain means."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.replication.geometry import FaceGeometry
from emogen.analysis.replication.mean_faces import LineFit, MeanFaceTest


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
        ("rms", +1, 0.0, TARGET, TARGET, "differs"),  # a precise zero: no effect of interest
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


@pytest.mark.parametrize(
    ("a", "b", "weaker", "n", "verdict"),
    [
        # the same face twice: the mean faces differ by sampling noise only
        (
            {"jawOpen": 0.4, "noseSneer": 0.24},
            {"jawOpen": 0.4, "noseSneer": 0.24},
            1.0,
            40,
            "holds",
        ),
        # b a little further along the line: between them less than their distance to the target
        (
            {"jawOpen": 0.4, "noseSneer": 0.24},
            {"jawOpen": 0.56, "noseSneer": 0.336},
            1.0,
            40,
            "partly",
        ),
        # a at the target's far side of b: further apart than b is from the target
        (
            {"jawOpen": 0.1, "noseSneer": 0.06},
            {"jawOpen": 0.6, "noseSneer": 0.36},
            1.0,
            40,
            "differs",
        ),
        # noisy runs, few of them: the interval spans the weaker level
        ({"jawOpen": 0.4, "noseSneer": 0.24}, {"jawOpen": 0.52, "noseSneer": 0.31}, 0.55, 6, None),
    ],
)
def test_between_reaches_each_verdict(ict_model, geometry, a, b, weaker, n, verdict) -> None:
    """'Nearly identical' mean faces: RMS between the mean faces over the smaller RMS to the
    target (0.8 jaw, 0.48 sneer), against 0.5 and ``weaker``; the estimate against the plain
    geometry on the plain means."""
    sd = 0.05 if verdict else 0.25
    fa, fb = _runs(ict_model, a, sd, 3, n), _runs(ict_model, b, sd, 4, n)
    target = np.broadcast_to(ict_model.rig.weights_from_names(TARGET), fa.shape)
    got = MeanFaceTest("between", level=0.5, weaker=weaker, resamples=60, geometry=geometry)(
        fa, fb, target
    )
    ma, mb, t = fa.mean(0), fb.mean(0), target[0]
    plain = geometry.rms_cm(ma, mb) / min(geometry.rms_cm(ma, t), geometry.rms_cm(mb, t))
    assert got.estimate == pytest.approx(plain)
    assert got.verdict == (verdict or "inconclusive"), got.text()


@pytest.mark.parametrize(
    ("kind", "face", "level", "upper", "verdict"),
    [
        ("residual", {"jawOpen": 0.4, "noseSneer": 0.24}, 0.35, 0.0, "holds"),  # on the line
        ("residual", {"mouthSmile": 0.9, "browInnerUp": 0.8}, 0.35, 0.0, "differs"),  # off
        ("residual", {"jawOpen": 0.8, "noseSneer": 0.12}, 0.0, 0.0, None),
        ("scale", {"jawOpen": 0.72, "noseSneer": 0.43}, 0.8, 1.25, "holds"),  # ×0.9
        ("scale", {"jawOpen": 0.4, "noseSneer": 0.24}, 0.8, 1.25, "differs"),  # ×0.5
        ("scale", {"jawOpen": 0.64, "noseSneer": 0.38}, 0.8, 1.25, None),  # ×0.8: across
    ],
)
def test_line_fit_reaches_each_verdict(ict_model, geometry, kind, face, level, upper, verdict):
    """Fig. 18's line: the residual and the scale of the mean face against the target's
    line, the estimate against a plain least-squares fit of the vertex displacements."""
    faces = _runs(ict_model, face, 0.03, 5)
    target = np.broadcast_to(ict_model.rig.weights_from_names(TARGET), faces.shape)
    if kind == "residual" and verdict is None:
        level = float(geometry.intensity_fit(faces.mean(0), target[0])[1])  # at its own value
    got = LineFit(kind, level, upper, resamples=60, geometry=geometry)(faces, target)
    v = ict_model.evaluate(
        np.stack([faces.mean(0), target[0], np.zeros_like(target[0])]).astype(np.float32)
    ).astype(np.float64)
    d_face, d_target = (v[0] - v[2]).ravel(), (v[1] - v[2]).ravel()
    s, *_ = np.linalg.lstsq(d_target[:, None], d_face, rcond=None)
    plain = {
        "scale": s[0],
        "residual": np.linalg.norm(d_face - s[0] * d_target) / np.linalg.norm(d_face),
    }
    assert got.estimate == pytest.approx(plain[kind], rel=1e-4, abs=5e-3)  # float32 vertices
    assert got.verdict == (verdict or "inconclusive"), got.text()


def test_line_fit_refuses_bad_input(geometry) -> None:
    with pytest.raises(ValueError, match="kind must be one of"):
        LineFit("slope", 0.3)
    with pytest.raises(ValueError, match="level < upper"):
        LineFit("scale", 1.25, 0.8)
    with pytest.raises(ValueError, match="the faces and the target"):
        LineFit("residual", 0.35, geometry=geometry)(np.zeros((4, 3)))
