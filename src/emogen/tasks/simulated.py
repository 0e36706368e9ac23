"""Simulated participants for every task: each with their own internal prototype per emotion
and choice noise, answering what the page shows (the same view a person gets).

The model (stated so an analysis can be checked against it):

* **Prototypes.** The population prototype of an emotion is its building blocks in the rig
  (:attr:`emogen.model.rig.Rig.emotions`: core genes at ``core``, optional genes at
  ``optional``). A participant's own prototype adds N(0, ``spread``²) to each of those genes,
  clipped to [0, 1]: individual differences within the emotion's own facial actions.
* **Evolve.** Faces are compared in gene space (Euclidean distance, the paper's ED on unique
  core genes; a shown face's genes are recovered from its shape weights). The participant picks
  like a softmax (Plackett–Luce) chooser with temperature ``select_noise``: the elite is face i
  with probability ∝ exp(−dᵢ / T), then the others likewise from the rest (Gumbel trick), as
  many as ``n_selected`` (clipped to the study's limits). The final face is rated 1…points by
  its distance to the prototype.
* **Categorise.** The face is labelled k with probability ∝ exp(−dₖ / ``label_noise``), dₖ its
  distance to the participant's prototype of label k; "none of these" is never chosen.
  Intensity: the face's projection on the chosen prototype (0…1 → 1…points); confidence: the
  chosen label's probability (→ 1…points).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from emogen.errors import ConfigError
from emogen.model.rig import Rig


@dataclass(frozen=True)
class SimulatedDesign:
    """What simulated participants share: the prototype model and their noise."""

    #: SD of a participant's prototype genes around the population prototype.
    spread: float = 0.5
    #: Softmax temperature of GA choices and of labels (gene-space ED units).
    select_noise: float = 0.05
    label_noise: float = 0.15
    #: Faces selected per generation (elite included), clipped to the study's limits.
    n_selected: int = 3
    #: Population prototype values of an emotion's core and optional genes.
    core: float = 0.8
    optional: float = 0.3

    def __post_init__(self) -> None:
        for name in ("spread", "select_noise", "label_noise"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ConfigError(f"{name} must be a finite number >= 0; got {value}")


def population_prototypes(
    rig: Rig, emotions: Sequence[str], design: SimulatedDesign, eye_motion: bool = True
) -> dict[str, np.ndarray]:
    """The population prototype (n_genes,) of each emotion, from the rig's building blocks."""
    names = rig.gene_names(eye_motion)
    index = {g: i for i, g in enumerate(names)}
    out = {}
    for emotion in emotions:
        if emotion not in rig.emotions:
            raise ConfigError(
                f"simulated participants need the rig's building blocks of '{emotion}'; rig "
                f"'{rig.name}' defines: {', '.join(rig.emotions)}"
            )
        spec = rig.emotions[emotion]
        p = np.zeros(len(names))
        p[[index[g] for g in spec.optional if g in index]] = design.optional
        p[[index[g] for g in spec.core if g in index]] = design.core
        out[emotion] = p
    return out


def own_prototypes(
    population: Mapping[str, np.ndarray], design: SimulatedDesign, rng: np.random.Generator
) -> dict[str, np.ndarray]:
    """A participant's prototypes: the population's, their emotion's genes moved by
    N(0, spread²) and clipped to [0, 1]."""
    out = {}
    for emotion, p in population.items():
        active = p > 0
        own = p.copy()
        own[active] = np.clip(p[active] + rng.normal(0.0, design.spread, active.sum()), 0, 1)
        out[emotion] = own
    return out


@dataclass
class SimulatedParticipant:
    """One simulated participant: their prototypes (by emotion, in gene space) and their
    own random stream (every choice is drawn from it, in the order the study asks)."""

    prototypes: dict[str, np.ndarray]
    design: SimulatedDesign
    rig: Rig
    eye_motion: bool
    rng: np.random.Generator

    def genes(self, weights: np.ndarray) -> np.ndarray:
        """(n_faces, n_genes) genes of faces given by full weights (shapes first)."""
        w = np.atleast_2d(np.asarray(weights, dtype=np.float64))[:, : len(self.rig.shape_names)]
        return self.rig.contract(w, self.eye_motion)

    def _order(self, distances: np.ndarray, temperature: float) -> np.ndarray:
        """Indices in the order a softmax chooser picks them (Gumbel trick)."""
        if temperature == 0:
            return np.argsort(distances, kind="stable")
        keys = distances / temperature - self.rng.gumbel(size=len(distances))
        return np.argsort(keys, kind="stable")

    def select(
        self, weights: np.ndarray, emotion: str, limits: tuple[int, int]
    ) -> tuple[int, list[int]]:
        """(elite position, other positions) among the shown faces."""
        d = np.linalg.norm(self.genes(weights) - self.prototypes[emotion], axis=1)
        lo, hi = limits
        n = int(np.clip(self.design.n_selected, lo, hi))
        order = self._order(d, self.design.select_noise)[:n]
        return int(order[0]), [int(i) for i in order[1:]]

    def rate(self, weights: np.ndarray, emotion: str, points: int) -> int:
        """How well the final face shows the emotion: 1 … points (closer: higher)."""
        proto = self.prototypes[emotion]
        d = float(np.linalg.norm(self.genes(weights)[0] - proto))
        scale = float(np.linalg.norm(proto)) or 1.0
        return round(points - (points - 1) * min(1.0, d / scale))

    def categorise(
        self, weights: np.ndarray, labels: Sequence[str], points: int
    ) -> tuple[str, int, int]:
        """(label, intensity, confidence) for a face: a softmax over the distances to the
        participant's prototypes of the labels offered."""
        g = self.genes(weights)[0]
        d = np.array([np.linalg.norm(g - self.prototypes[label]) for label in labels])
        k = int(self._order(d, self.design.label_noise)[0])
        t = max(self.design.label_noise, 1e-12)
        p = np.exp(-(d - d.min()) / t)
        p /= p.sum()
        proto = self.prototypes[labels[k]]
        along = float(g @ proto / max(float(proto @ proto), 1e-12))
        intensity = round(1 + (points - 1) * min(1.0, max(0.0, along)))
        confidence = round(1 + (points - 1) * float(p[k]))
        return labels[k], intensity, confidence


@dataclass(frozen=True)
class SimulatedPeople:
    """Who answers a simulated session's screens: the ``maker`` of faces (the GA's choices and
    ratings) and the ``judge`` of faces (labels; the same person unless the study simulates
    judges whose prototypes are another participant's)."""

    maker: SimulatedParticipant
    judge: SimulatedParticipant
