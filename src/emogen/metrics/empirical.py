"""The empirical metrics (Section IV-B2), trained on a set of faces.

* :class:`PCASpace` — β = PCA(α), a scikit-learn PCA of full weight vectors α fitted on a
  training set, keeping the components that explain ``variance`` of it (99% by default, as in
  the paper). ``ed`` is ED(β₁, β₂) (eq. 11 in PCA space), ``std_ed`` is std_ED (eq. 15); the
  Mahalanobis distance in PCA space (eq. 14) equals std_ED, since PCA diagonalises S.
* :class:`VertexMahalanobis` — MD(F₁, F₂) (eq. 16) on vertex offsets δV = V − V₀.

**Eq. 16 without a 3N × 3N matrix.** A blend face's offsets are δV = α D (D: the (S, 3N)
deltas; the eyeball gaze rotation is left out, i.e. ``evaluate(gaze=False)``), so every
training offset, and every difference δV₁ − δV₂, lies in the row space of D, of dimension
r <= S. With G = D Dᵀ = Q diag(g) Qᵀ, the coordinates y = α Q diag(√g) (r of them) are
orthonormal coordinates of that row space: ‖α D‖ = ‖y‖. The PCA of the training offsets in
3N-space *is* the PCA of the training y (same eigenvalues λᵢ, directions mapped by an
isometry), so nothing of size 3N × 3N (or even n × 3N) is ever formed.

**Regularisation.** The 3N × 3N covariance S of n training faces has rank <= min(n − 1, r)
and cannot be inverted. We keep the k principal components that explain ``variance`` of the
training variance (99%) and add a ridge λ to every direction:

    S_λ = U_k diag(λ₁..λ_k) U_kᵀ + λ I,    λ = ridge · tr(S) / 3N

(``ridge`` = 1 by default: λ is the average per-coordinate training variance). Then, with
x = δV₁ − δV₂ and pᵢ = uᵢ·x,

    MD² = xᵀ S_λ⁻¹ x = Σᵢ pᵢ² / (λᵢ + λ) + (‖x‖² − Σᵢ pᵢ²) / λ

— directions the training faces did not vary along are far (variance λ), directions they
varied along are scaled by their variance. With ``variance=1`` all components are kept and
S_λ = S + λ I.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from emogen.errors import ConfigError, ShapeError

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

#: Components whose variance is below this fraction of the largest are dropped (rank-deficient
#: training sets would otherwise divide by ~0 in std_ED).
RELATIVE_TOLERANCE = 1e-10


def _check_training(weights: np.ndarray, n_shapes: int | None = None) -> np.ndarray:
    w = np.asarray(weights, dtype=np.float64)
    if w.ndim != 2 or (n_shapes is not None and w.shape[1] != n_shapes):
        want = f"(n_faces, {n_shapes})" if n_shapes is not None else "(n_faces, n_shapes)"
        raise ShapeError(f"training weights must have shape {want}; got {w.shape}")
    if len(w) < 2:
        raise ConfigError(f"a training set needs at least 2 faces; got {len(w)}")
    if not np.all(np.isfinite(w)):
        raise ConfigError("training weights contain NaN or infinity")
    return w


def _check_variance(variance: float) -> None:
    if not 0.0 < variance <= 1.0:
        raise ConfigError(f"variance must be in (0, 1]; got {variance}")


def fit_pca(x: np.ndarray, variance: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """scikit-learn PCA of the rows of x: (mean (d,), components (k, d), variances (k,)).

    Keeps the fewest components whose cumulative explained-variance ratio exceeds ``variance``
    (all with 1.0), then drops those with a variance below RELATIVE_TOLERANCE of the largest.
    Variances are sample variances (n − 1 in the denominator), as in ``numpy.cov``.
    """
    from sklearn.decomposition import PCA

    _check_variance(variance)
    if not np.any(np.ptp(x, axis=0) > 0):
        raise ConfigError("the training faces do not vary: every one is the same")
    pca = PCA(n_components=None if variance >= 1.0 else variance, svd_solver="full").fit(x)
    var = pca.explained_variance_
    keep = var > RELATIVE_TOLERANCE * max(float(var.max(initial=0.0)), np.finfo(float).tiny)
    if not keep.any():
        raise ConfigError("the training faces do not vary: every one is the same")
    return pca.mean_.copy(), pca.components_[keep].copy(), var[keep].copy()


def _rows(a: np.ndarray, b: np.ndarray, d: int, name: str) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape[-1] != d or b.shape[-1] != d:
        raise ShapeError(f"{name} needs weights (n_faces, {d}); got {a.shape} and {b.shape}")
    return a, b


@dataclass(frozen=True, eq=False)
class PCASpace:
    """β = PCA(α) fitted on training faces (eqs. 14–15). Arrays: mean (S,), components (k, S)
    (orthonormal rows), variances (k,) — each component's training variance σᵢ²."""

    mean: np.ndarray
    components: np.ndarray
    variances: np.ndarray
    n_train: int
    variance: float

    @classmethod
    def fit(cls, weights: np.ndarray, *, variance: float = 0.99) -> PCASpace:
        """PCA of training full weight vectors (n_faces, n_shapes)."""
        w = _check_training(weights)
        mean, comps, var = fit_pca(w, variance)
        return cls(mean, comps, var, len(w), variance)

    @property
    def n_components(self) -> int:
        return len(self.variances)

    def transform(self, weights: np.ndarray) -> np.ndarray:
        """β = (α − mean) Cᵀ: (n_faces, S) → (n_faces, k)."""
        return (np.asarray(weights, dtype=np.float64) - self.mean) @ self.components.T

    def ed(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """ED(β₁, β₂): Euclidean distance of the PCA coordinates, row by row → (n_faces,)."""
        a, b = _rows(a, b, self.mean.shape[0], "PCASpace.ed")
        return np.sqrt((((a - b) @ self.components.T) ** 2).sum(-1))

    def std_ed(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """std_ED(β₁, β₂) = sqrt(Σᵢ (β₁ᵢ − β₂ᵢ)² / σᵢ²) (eq. 15), row by row → (n_faces,)."""
        a, b = _rows(a, b, self.mean.shape[0], "PCASpace.std_ed")
        return np.sqrt(((((a - b) @ self.components.T) ** 2) / self.variances).sum(-1))


@dataclass(frozen=True, eq=False)
class VertexMahalanobis:
    """MD(F₁, F₂) (eq. 16) in vertex-offset space, low-rank and ridge-regularised (see module).

    coords : (S, r) maps full weights to orthonormal row-space coordinates y = α · coords;
    components : (k, r) principal directions of the training y; variances : (k,) their λᵢ;
    ridge_variance : λ, the variance given to every other direction.
    """

    coords: np.ndarray
    components: np.ndarray
    variances: np.ndarray
    ridge_variance: float
    n_train: int
    variance: float
    ridge: float

    @classmethod
    def fit(
        cls,
        deltas: np.ndarray,
        weights: np.ndarray,
        *,
        variance: float = 0.99,
        ridge: float = 1.0,
    ) -> VertexMahalanobis:
        """Fit from blendshape deltas (S, N, 3) or (S, 3N) and training weights (n, S)."""
        if ridge <= 0:
            raise ConfigError(f"ridge must be > 0; got {ridge}")
        d = np.asarray(deltas, dtype=np.float64)
        d = d.reshape(d.shape[0], -1)
        w = _check_training(weights, d.shape[0])
        g, q = np.linalg.eigh(d @ d.T)
        keep = g > RELATIVE_TOLERANCE * max(float(g.max(initial=0.0)), np.finfo(float).tiny)
        coords = q[:, keep] * np.sqrt(g[keep])
        y = w @ coords
        total = float(y.var(axis=0, ddof=1).sum())  # tr(S) of the 3N-space covariance
        if total <= 0:
            raise ConfigError("the training faces do not vary: every one is the same")
        _, comps, var = fit_pca(y, variance)
        lam = ridge * total / d.shape[1]
        return cls(coords, comps, var, lam, len(w), variance, ridge)

    @classmethod
    def from_model(
        cls, model: FaceModel, weights: np.ndarray, *, variance: float = 0.99, ridge: float = 1.0
    ) -> VertexMahalanobis:
        return cls.fit(model.deltas, weights, variance=variance, ridge=ridge)

    @property
    def n_components(self) -> int:
        return len(self.variances)

    def __call__(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """MD per face pair: a, b (n_faces, S) or (S,) full weights, broadcast → (n_faces,)."""
        a, b = _rows(a, b, self.coords.shape[0], "VertexMahalanobis")
        dy = (a - b) @ self.coords
        p = dy @ self.components.T
        p2 = (p**2).sum(-1)
        rest = np.maximum((dy**2).sum(-1) - p2, 0.0)
        md2 = ((p**2) / (self.variances + self.ridge_variance)).sum(-1)
        return np.sqrt(md2 + rest / self.ridge_variance)
