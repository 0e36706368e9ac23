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

Use it through the model: ``model.correct(weights)`` and ``model.evaluate(weights, correct=True)``.
"""

from emogen.correct.apply import CorrectionResult, Corrector
from emogen.correct.correctives import Correctives, build_correctives, correctives_for

__all__ = ["CorrectionResult", "Correctives", "Corrector", "build_correctives", "correctives_for"]
