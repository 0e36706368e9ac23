"""Automatic correctives (paper Section III-A): combinational and lip/teeth collision.

* :mod:`~emogen.correct.combinational` — product-activated correctives, derived from the
  geometry (double counting), artist-made ones from the rig, companion caps;
* :mod:`~emogen.correct.lips` — the mouth line, upper/lower lip layout (geodesic);
* :mod:`~emogen.correct.collision` — the eight collision shapes, anchors, detection and depths
  (eqs. 2–4), over :mod:`~emogen.correct.raycast`;
* :mod:`~emogen.correct.solve` — eq. 5 and the detect–solve loop;
* :mod:`~emogen.correct.correctives` — the :class:`Correctives` bundle, cached on disk;
* :mod:`~emogen.correct.apply` — :class:`Corrector` and :class:`CorrectionResult`;
* :mod:`~emogen.correct.measure` — independent measures (interpenetration, plausibility).

* :mod:`~emogen.correct.faces` — the entry points, taking the model as an argument:
  ``correct_faces(model, weights)``, ``corrected_vertices(model, result)``,
  ``evaluate_corrected(model, weights)``, ``model_correctives(model)``.
"""

from emogen.correct.apply import CorrectionResult, Corrector
from emogen.correct.correctives import Correctives, build_correctives, correctives_for
from emogen.correct.faces import (
    correct_faces,
    corrected_vertices,
    corrector_for,
    evaluate_corrected,
    model_correctives,
)

__all__ = [
    "CorrectionResult",
    "Correctives",
    "Corrector",
    "build_correctives",
    "correct_faces",
    "corrected_vertices",
    "correctives_for",
    "corrector_for",
    "evaluate_corrected",
    "model_correctives",
]
