"""Where the face's features are on the rest mesh: landmarks, brows, lips, head axis, ears.

Everything is in the model's centimetres, derived from the identity's neutral mesh, its 68
landmarks (jaw 0-16, brows 17-26, nose 27-35, eyes 36-47, outer lips 48-59, inner lips 60-67)
and the brow shapes' motion: the brow band follows the landmarks across and, vertically, the
line where ``browDown``/``browInnerUp``/``browOuterUp`` move the skin most.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.errors import ShapeError
from emogen.model.face import FaceModel
from emogen.model.geometry import sphere_fit

BROW_SHAPES = ("browDown", "browInnerUp", "browOuterUp")
RIGHT_BROW = (21, 20, 19, 18, 17)  # subject's right (x < 0), head (medial) first
LEFT_BROW = (22, 23, 24, 25, 26)
OUTER_LIPS = tuple(range(48, 60))
INNER_LIPS = tuple(range(60, 68))


def catmull_rom(points: np.ndarray, per_segment: int = 16, closed: bool = True) -> np.ndarray:
    """A smooth curve (n·per_segment, d) through ``points`` (n, d) (uniform Catmull-Rom)."""
    p = np.asarray(points, dtype=np.float64)
    n = len(p)
    idx = np.arange(n) if closed else np.arange(n - 1)
    t = np.linspace(0, 1, per_segment, endpoint=False)[:, None]
    out = []
    for i in idx:
        p0 = p[(i - 1) % n] if closed or i > 0 else p[0]
        p1, p2 = p[i], p[(i + 1) % n]
        p3 = p[(i + 2) % n] if closed or i + 2 < n else p[-1]
        out.append(
            0.5
            * (
                2 * p1
                + (-p0 + p2) * t
                + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t**2
                + (-p0 + 3 * p1 - 3 * p2 + p3) * t**3
            )
        )
    if not closed:
        out.append(p[-1:])
    return np.concatenate(out)


@dataclass(frozen=True)
class Brow:
    side: int  # +1 subject's left (x > 0), −1 right
    #: centreline samples from head (medial) to tail, in cylindrical (s, y) cm
    line: np.ndarray  # (n, 2)
    #: band height (cm) at each centreline sample before the appearance's thickness factor
    height: np.ndarray  # (n,)


@dataclass(frozen=True)
class FaceFeatures:
    landmarks: np.ndarray  # (68, 3) cm
    axis: np.ndarray  # (x, z) of the head's vertical axis (cranium centre)
    radius: float  # cranium radius (cm): cylindrical s = radius · θ
    brows: tuple[Brow, Brow]
    lip_outline: np.ndarray  # (n, 2) closed outer lip contour, x-y plane (cm)
    lip_front_z: float  # lips lie in front of this depth
    eye_centres: np.ndarray  # (2, 3) mean of each eye's six landmarks
    brow_top: float  # highest brow landmark y

    def cylindrical(self, points: np.ndarray) -> np.ndarray:
        """Points (..., 3) → (..., 2) (s, y): arc length around the head axis (0 in front,
        + towards the subject's left) and height."""
        theta = np.arctan2(points[..., 0] - self.axis[0], points[..., 2] - self.axis[1])
        return np.stack([self.radius * theta, points[..., 1]], -1)

    def theta_deg(self, points: np.ndarray) -> np.ndarray:
        return np.degrees(np.arctan2(points[..., 0] - self.axis[0], points[..., 2] - self.axis[1]))


def brow_motion(model: FaceModel) -> np.ndarray:
    """(V,) summed displacement (cm) of the brow shapes (both sides) at unit weight."""
    names = [n for n in model.shape_names if n.split("_")[0] in BROW_SHAPES]
    if not names:
        raise ShapeError(f"model '{model.name}' has none of the brow shapes {BROW_SHAPES}")
    idx = [model.shape_names.index(n) for n in names]
    return np.linalg.norm(model.deltas[idx], axis=-1).sum(0)


def _brow(
    model: FaceModel,
    features_cyl: np.ndarray,
    lm: np.ndarray,
    ids: tuple[int, ...],
    motion: np.ndarray,
) -> Brow:
    """Brow band along the landmarks; its height centred between the landmarks and the crest
    of the brow shapes' motion, column by column."""
    face = model.regions["face"].vertices
    pts = model.neutral[face].astype(np.float64)
    cyl = features_cyl[face]
    mot = motion[face]
    side = 1 if lm[ids[0], 0] > 0 else -1
    marks = features_cyl[model.landmarks[list(ids)]]
    front = pts[:, 2] > lm[list(ids), 2].min() - 2.0
    crest = []
    for s, y in marks:
        near = front & (np.abs(cyl[:, 0] - s) < 0.3) & (np.abs(cyl[:, 1] - y) < 1.5)
        crest.append(cyl[near][np.argmax(mot[near]), 1] if near.any() else y)
    ys = 0.5 * (marks[:, 1] + np.asarray(crest))
    ctrl = np.c_[marks[:, 0], ys]
    # Extend past the head (towards the nose bridge) a little: the landmarks start inside it.
    head = ctrl[0] + (ctrl[0] - ctrl[1]) * 0.25
    line = catmull_rom(np.vstack([head, ctrl]), per_segment=12, closed=False)
    t = np.linspace(0.0, 1.0, len(line))
    # Band height (cm): full at the head and body, tapering to a narrow tail.
    height = np.interp(t, [0.0, 0.12, 0.45, 0.8, 1.0], [0.85, 1.0, 0.9, 0.6, 0.3])
    return Brow(side, line, height)


def face_features(model: FaceModel) -> FaceFeatures:
    """The features of ``model``'s neutral (needs ICT's 68 landmarks and its regions)."""
    if len(model.landmarks) != 68 or not {"face", "head_neck"} <= set(model.regions):
        raise ShapeError(
            f"the textured appearance needs the model's 68 facial landmarks and its face and "
            f"head_neck regions; model '{model.name}' has {len(model.landmarks)} landmarks"
        )
    n = model.neutral.astype(np.float64)
    lm = n[model.landmarks]
    head = n[model.regions["head_neck"].vertices]
    eye_y = lm[36:48, 1].mean()
    centre, radius = sphere_fit(head[head[:, 1] > eye_y + 3.0])
    axis = np.array([0.0, centre[2]])
    feats = FaceFeatures(
        landmarks=lm,
        axis=axis,
        radius=radius,
        brows=None,  # type: ignore[arg-type]
        lip_outline=catmull_rom(lm[list(OUTER_LIPS), :2], per_segment=16, closed=True),
        lip_front_z=float(lm[list(OUTER_LIPS), 2].min() - 1.5),
        eye_centres=np.stack([lm[36:42].mean(0), lm[42:48].mean(0)]),
        brow_top=float(lm[17:27, 1].max()),
    )
    cyl = feats.cylindrical(n)
    motion = brow_motion(model)
    brows = (_brow(model, cyl, lm, RIGHT_BROW, motion), _brow(model, cyl, lm, LEFT_BROW, motion))
    return FaceFeatures(**{**feats.__dict__, "brows": brows})
