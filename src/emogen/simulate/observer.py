"""Simulated observers: they select faces as a participant would, by a similarity metric.

An observer ranks the shown faces by their distance to a target under a metric
(:func:`make_metric`: ED, CD, vertex RMS, PCA ED, standardised ED, Mahalanobis) and selects
``count(g)`` of them — the paper's schedule (2, then 4 in generations 1–5, then 5) or any
other; in the last generation only the elite counts. The classical variant's observer ranks
the whole population.

**Choice noise.** With a temperature T > 0 the observer is a softmax (Plackett–Luce) chooser:
the elite is face i with probability ∝ exp(−dᵢ / T), the next selection is drawn likewise from
the remaining faces, and so on. It is sampled with the Gumbel trick — order the faces by
dᵢ / T − Gᵢ, Gᵢ ~ Gumbel(0, 1) i.i.d. — which gives exactly that distribution of orders. T is
in the metric's units (CD lies in [0, 2]; T = 0.05 makes a CD difference of 0.05 an e-fold in
odds). The Gumbel draws come from the run's own observer stream
(:func:`emogen.rng.observer_rng`), independent of the GA's.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from emogen.config import MetricConfig, SimulationConfig
from emogen.errors import ConfigError, ShapeError
from emogen.ga.population import Population
from emogen.metrics import (
    PCASpace,
    VertexMahalanobis,
    VertexRMS,
    cosine_distance,
    gene_euclidean_distance,
)
from emogen.model.rig import Rig

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

DESCRIPTIONS = {
    "cd": "cosine distance (eq. 12) on full weight vectors",
    "ed": "Euclidean distance (eq. 11) on unique core genes",
    "vertex_rms": "vertex RMS (eq. 13) over all vertices (Gram matrix of the deltas, eyeballs "
    "in closed form)",
    "pca_ed": "Euclidean distance in PCA space (eq. 14 with identity S) of full weight vectors",
    "std_ed": "standardised Euclidean distance in PCA space (eq. 15)",
    "mahalanobis": "Mahalanobis distance (eq. 16) on vertex offsets, low-rank + ridge",
}


@dataclass(frozen=True)
class Metric:
    """A metric between faces given by full weights: ``metric(weights (B, S), target (S,))``
    → (B,) distances. Picklable (for worker processes)."""

    name: str
    description: str
    distance: Callable[[np.ndarray, np.ndarray], np.ndarray]
    details: dict[str, object]

    def __call__(self, weights: np.ndarray, target: np.ndarray) -> np.ndarray:
        return np.asarray(self.distance(weights, target), dtype=np.float64)


def make_metric(
    config: MetricConfig | str,
    rig: Rig,
    *,
    model: FaceModel | None = None,
    eye_motion: bool = True,
    training: np.ndarray | None = None,
    correctives: np.ndarray | None = None,
) -> Metric:
    """The metric named by ``config``; vertex metrics need ``model``, empirical ones a training
    set (``training`` weights (n, S), else read from ``config.training``).

    ``correctives`` (C, N, 3): the faces are corrected, their full weight vectors (…, S + C)
    end with C corrective weights. CD compares the whole vectors, vertex RMS blends the
    correctives too (still exact); ED, PCA ED, std_ED and Mahalanobis use the S shape weights.
    """
    cfg = MetricConfig(name=config) if isinstance(config, str) else config  # type: ignore[arg-type]
    name = cfg.name
    details: dict[str, object] = {}
    fn: Callable[[np.ndarray, np.ndarray], np.ndarray]
    if name in ("pca_ed", "std_ed", "mahalanobis") and training is None:
        if cfg.training is None:
            raise ConfigError(f"metric '{name}' needs a training set (metric.training)")
        from emogen.simulate.targets import file_digest, read_faces

        training = read_faces(cfg.training, rig, query=cfg.query)
        details.update(training=str(cfg.training), sha256=file_digest(cfg.training))
    if name == "cd":
        fn = cosine_distance
    elif name == "ed":
        fn = functools.partial(_gene_ed, rig, eye_motion)
    elif name == "vertex_rms":
        fn = VertexRMS(_model(model, name), gaze=cfg.gaze, extra_deltas=correctives)
        details.update(gaze=cfg.gaze)
    elif name in ("pca_ed", "std_ed"):
        space = PCASpace.fit(np.asarray(training), variance=cfg.variance)
        fn = space.ed if name == "pca_ed" else space.std_ed
        details.update(variance=cfg.variance, components=space.n_components, n_train=space.n_train)
    else:
        md = VertexMahalanobis.from_model(
            _model(model, name), np.asarray(training), variance=cfg.variance, ridge=cfg.ridge
        )
        fn = md
        details.update(
            variance=cfg.variance,
            ridge=cfg.ridge,
            ridge_variance=md.ridge_variance,
            components=md.n_components,
            n_train=md.n_train,
        )
    if correctives is not None and name not in ("cd", "vertex_rms"):
        fn = _Shapes(fn, len(rig.shape_names))
    return Metric(name, DESCRIPTIONS[name], fn, details)


@dataclass(frozen=True)
class _Shapes:
    """A metric on the first ``n`` columns (the shapes of corrected full weight vectors)."""

    fn: Callable[[np.ndarray, np.ndarray], np.ndarray]
    n: int

    def __call__(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return self.fn(np.asarray(a)[..., : self.n], np.asarray(b)[..., : self.n])


def _model(model: FaceModel | None, name: str) -> FaceModel:
    if model is None:
        raise ConfigError(f"metric '{name}' works on vertices: it needs the face model")
    return model


def _gene_ed(rig: Rig, eye_motion: bool, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return gene_euclidean_distance(rig, a, b, eye_motion=eye_motion)


# ---- choosing ----------------------------------------------------------------------------------
def selection_count(config: SimulationConfig, generation: int, n_faces: int) -> int:
    """Faces the observer selects in a generation: 1 in the last, all (a ranking) for the
    classical variant, else the schedule's count (at most the population)."""
    if generation >= config.ga.generations:
        return 1
    if config.ga.variant == "classical":
        return n_faces
    return min(config.selections_at(generation), n_faces)


def choice_order(
    distances: np.ndarray, temperature: float = 0.0, gumbel: np.ndarray | None = None
) -> np.ndarray:
    """Faces in the order the observer picks them, row by row: distances (R, N) → (R, N) int.

    T = 0: closest first (ties keep slot order). T > 0: the order of dᵢ / T − Gᵢ, with
    ``gumbel`` (R, N) standard Gumbel draws — a softmax choice without replacement.
    """
    d = np.asarray(distances, dtype=np.float64)
    if temperature == 0:
        return np.argsort(d, axis=-1, kind="stable")
    if gumbel is None or gumbel.shape != d.shape:
        raise ShapeError(f"choice noise needs Gumbel draws of shape {d.shape}")
    return np.argsort(d / temperature - gumbel, axis=-1, kind="stable")


class Observer:
    """Selects faces of an engine's population toward ``target`` by ``metric`` (one run).

    ``count(g)`` faces per generation, one in generation ``final``; ``ranking=True`` (the
    classical variant) ranks every face. With ``temperature`` > 0 it draws its choices from
    ``rng`` (Gumbel draws, N per generation). The vectorised runner reproduces its choices.
    """

    def __init__(
        self,
        metric: Callable[[np.ndarray, np.ndarray], np.ndarray],
        target: np.ndarray,
        count: Callable[[int], int],
        *,
        final: int,
        ranking: bool = False,
        temperature: float = 0.0,
        rng: np.random.Generator | None = None,
    ) -> None:
        if temperature > 0 and rng is None:
            raise ConfigError("an observer with choice noise needs rng")
        self.metric = metric
        self.target = np.asarray(target, dtype=np.float64)
        self.count = count
        self.final = final
        self.ranking = ranking
        self.temperature = temperature
        self.rng = rng

    def choose(
        self, population: Population, weights: np.ndarray | None = None
    ) -> tuple[int, list[int], float]:
        """(elite id, other ids in choice order, the elite's distance to the target).

        ``weights`` (n_faces, n_shapes): what is shown, if not ``population.weights`` (e.g.
        corrected faces).
        """
        w = population.weights if weights is None else weights
        distances = np.asarray(self.metric(w, self.target), dtype=np.float64)
        gumbel = None
        if self.temperature > 0 and self.rng is not None:
            gumbel = self.rng.gumbel(size=len(distances))[None]
        order = choice_order(distances[None], self.temperature, gumbel)[0]
        ids = population.ids[order]
        g = population.generation
        if g >= self.final:
            n = 1
        elif self.ranking:
            n = len(ids)
        else:
            n = min(self.count(g), len(ids))
        return int(ids[0]), [int(i) for i in ids[1:n]], float(distances[order[0]])


def rank_by_cosine(weights: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Faces ordered by cosine distance to the target, closest first (ties: slot order).

    weights : (n_faces, n_shapes) float, full weight vectors; target : (n_shapes,) float.
    Returns (order (n_faces,) int, distances (n_faces,) float in slot order).
    """
    weights = np.asarray(weights, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    if weights.ndim != 2 or target.shape != (weights.shape[1],):
        raise ShapeError(
            f"weights (n_faces, n_shapes) and target (n_shapes,) must agree; got "
            f"{weights.shape} and {target.shape}"
        )
    distances = cosine_distance(weights, target[None, :])
    return np.argsort(distances, kind="stable"), distances


class CosineObserver(Observer):
    """Selects the faces closest to a target by CD (eq. 12) on full weight vectors."""

    def __init__(
        self,
        target: np.ndarray,
        count: Callable[[int], int],
        *,
        final: int,
        ranking: bool = False,
    ) -> None:
        super().__init__(cosine_distance, target, count, final=final, ranking=ranking)
