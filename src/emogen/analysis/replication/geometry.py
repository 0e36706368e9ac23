"""Comparing faces on the mesh: vertex RMS in cm, the intensity line of a target, and the
ratio of two genes in a face."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from emogen.metrics import VertexRMS
    from emogen.model.face import FaceModel


@dataclass(eq=False)
class FaceGeometry:
    """Geometric comparisons of faces (full weights) on ``model``."""

    model: FaceModel
    _vertex_rms: VertexRMS | None = field(default=None, repr=False)

    def rms_cm(self, a: np.ndarray, b: np.ndarray) -> float:
        """Vertex RMS (eq. 13) between two faces, in cm."""
        if self._vertex_rms is None:
            from emogen.metrics import VertexRMS

            self._vertex_rms = VertexRMS(self.model)
        return float(self._vertex_rms(a, b))

    def max_cm(self, a: np.ndarray, b: np.ndarray) -> float:
        """The largest vertex distance between two faces, in cm (the paper's 'local error')."""
        v = self.model.evaluate(np.stack([a, b]).astype(np.float32)).astype(np.float64)
        return float(np.linalg.norm(v[0] - v[1], axis=-1).max())

    def intensity_fit(self, face: np.ndarray, target: np.ndarray) -> tuple[float, float]:
        """How well ``face`` lies on the target's intensity line, geometrically: the scale s*
        that best maps the target's vertex displacement (from the neutral) onto the face's, and
        the share of the face's own displacement off the line, ‖d_face − s* d_target‖ /
        ‖d_face‖ (the sine of the angle between the two displacements: 0 exactly a scaled
        target, 1 at right angles; 1 for a neutral face, which has no direction)."""
        s, r = self.intensity_fits(np.asarray(face)[None], target)
        return float(s[0]), float(r[0])

    def intensity_fits(
        self, faces: np.ndarray, target: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`intensity_fit` of each of ``faces`` (k, S): (scales (k,), residuals (k,))."""
        t = np.asarray(target)
        v = self.model.evaluate(
            np.vstack([faces, t[None], np.zeros_like(t)[None]]).astype(np.float32)
        )
        v = v.astype(np.float64).reshape(len(v), -1)
        d_faces, d_target = v[:-2] - v[-1], v[-2] - v[-1]
        s = d_faces @ d_target / (d_target @ d_target)
        off = np.linalg.norm(d_faces - s[:, None] * d_target, axis=1)
        size = np.linalg.norm(d_faces, axis=1)
        return s, np.divide(off, size, out=np.ones_like(off), where=size > 0)

    def gene_ratio(self, w: np.ndarray, gene: str, over: str) -> float:
        """Mean weight of ``gene``'s shapes over that of ``over``'s (NaN when ``over`` is off)."""
        below = self._gene(w, over)
        return self._gene(w, gene) / below if below > 1e-9 else float("nan")

    def _gene(self, w: np.ndarray, gene: str) -> float:
        rig = self.model.rig
        idx = [rig.shape_names.index(s) for g in rig.genes if g.name == gene for s in g.shapes]
        return float(np.mean(w[idx]))
