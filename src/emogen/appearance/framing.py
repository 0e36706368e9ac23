"""The span a ``face`` framing fits: from the chin to the hairline of an identity's neutral."""

from __future__ import annotations

import numpy as np

from emogen.appearance.features import face_features
from emogen.appearance.paint import hairline_height
from emogen.appearance.params import Appearance
from emogen.model.face import FaceModel


def face_span(model: FaceModel, appearance: Appearance) -> tuple[float, float, float]:
    """(hairline y, chin y, depth z) in cm: the front hairline's height on the midline (the
    painted one, or where it would be for a bald face), the chin landmark's height, and the
    mean depth of the two."""
    f = face_features(model)
    hair = float(hairline_height(np.array([0.0]), f, appearance)[0])
    chin = f.landmarks[8]
    return hair, float(chin[1]), float((chin[2] + f.landmarks[27, 2]) / 2)
