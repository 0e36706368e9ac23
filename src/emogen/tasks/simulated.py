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
* **Dynamic faces** (an evolve block with ``dynamic``). A participant's prototype of an emotion
  also has a time course: every gene of the emotion rises and falls on one curve of the
  genome's family (:func:`emogen.ga.genome.course`) with onset, peak and offset latencies
  (fractions of the clip) and acceleration and deceleration (``course``; an emotion's peak
  latency replaced by ``peak_at[emotion]``: planted timing differences; none: timing shared
  across emotions). The participant's own time course is the population's plus one deviation
  per participant, N(0, ``timing_spread``²) on each of the five, shared by their emotions
  (individual style; latencies kept in order at least ``MIN_GAP`` of the clip apart). Shown
  clips are compared with the prototype's over ``clip_samples`` times evenly over the clip:
  d = √(Σₜ ‖g(t) − p(t)‖² / Σₜ c(t)²), g(t) the face's gene weights at t (as the page plays
  them: its peak genes on its curves), p(t) the prototype's and c(t) its time course — with the
  prototype's own timing this is the static ED. Choices and ratings then go as above.
* **Categorise.** The face is labelled k with probability ∝ exp(−dₖ / ``label_noise``), dₖ its
  distance to the participant's prototype of label k; "none of these" is never chosen.
  Intensity: the face's projection on the chosen prototype (0…1 → 1…points); confidence: the
  chosen label's probability (→ 1…points).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from emogen.errors import ConfigError
from emogen.ga.genome import course
from emogen.model.rig import Rig

#: A prototype's time course, in order: onset, peak and offset latencies (fractions of the
#: clip), acceleration and deceleration (in [0, 1], as the genome's).
COURSE = ("onset", "peak", "offset", "acceleration", "deceleration")
#: The least time between a prototype's onset, peak and offset (fraction of the clip).
MIN_GAP = 0.05


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
    #: Population time course of every emotion (:data:`COURSE`; dynamic faces only).
    course: tuple[float, float, float, float, float] = (0.1, 0.45, 0.85, 0.5, 0.5)
    #: Planted timing: an emotion's population peak latency (fraction of the clip) in place of
    #: ``course``'s, e.g. ``{"fearful": 0.25, "sad": 0.65}``; empty: timing shared.
    peak_at: Mapping[str, float] = field(default_factory=dict)
    #: SD of a participant's deviation from the population's time course (each of the five).
    timing_spread: float = 0.05
    #: Times, evenly over the clip, at which a shown clip is compared with the prototype's.
    clip_samples: int = 26

    def __post_init__(self) -> None:
        for name in ("spread", "select_noise", "label_noise", "timing_spread"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ConfigError(f"{name} must be a finite number >= 0; got {value}")
        if len(self.course) != len(COURSE) or not all(0 <= v <= 1 for v in self.course):
            raise ConfigError(
                f"course must be {len(COURSE)} numbers in [0, 1] ({', '.join(COURSE)}); got "
                f"{self.course}"
            )
        on, peak, off = self.course[:3]
        if not on < peak < off:
            raise ConfigError(f"course needs onset < peak < offset; got {self.course[:3]}")
        for emotion, at in self.peak_at.items():
            if not (isinstance(at, int | float) and on < at < off):
                raise ConfigError(
                    f"peak_at['{emotion}'] must be a number between the course's onset {on} "
                    f"and offset {off} (fractions of the clip); got {at!r}"
                )
        if not 2 <= self.clip_samples <= 1000:
            raise ConfigError(f"clip_samples must be in [2, 1000]; got {self.clip_samples}")


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


def own_courses(
    emotions: Sequence[str], design: SimulatedDesign, rng: np.random.Generator
) -> dict[str, np.ndarray]:
    """A participant's time course (:data:`COURSE`, fractions of the clip) of each emotion: the
    population's (with ``peak_at``) plus one deviation N(0, timing_spread²) of each of the five
    shared by their emotions, slopes clipped to [0, 1] and latencies kept in order
    :data:`MIN_GAP` apart."""
    deviation = rng.normal(0.0, design.timing_spread, len(COURSE))
    out = {}
    for emotion in emotions:
        c = np.array(design.course, dtype=np.float64)
        c[1] = design.peak_at.get(emotion, c[1])
        c += deviation
        c[3:] = np.clip(c[3:], 0, 1)
        c[0] = np.clip(c[0], 0, 1 - 2 * MIN_GAP)
        c[1] = np.clip(c[1], c[0] + MIN_GAP, 1 - MIN_GAP)
        c[2] = np.clip(c[2], c[1] + MIN_GAP, 1)
        out[emotion] = c
    return out


def _course_at(rows: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Curves given as rows (…, 5) ``[t_on, t_peak, t_off, up, down]`` at times t (F,):
    (F, …)."""
    at = t.reshape((-1,) + (1,) * (rows.ndim - 1))
    return course(rows[..., 0], rows[..., 1], rows[..., 2], rows[..., 3], rows[..., 4], at)


@dataclass
class SimulatedParticipant:
    """One simulated participant: their prototypes (by emotion, in gene space), their time
    courses (by emotion, :data:`COURSE`; used where faces move) and their own random stream
    (every choice is drawn from it, in the order the study asks)."""

    prototypes: dict[str, np.ndarray]
    design: SimulatedDesign
    rig: Rig
    eye_motion: bool
    rng: np.random.Generator
    courses: dict[str, np.ndarray] = field(default_factory=dict)

    def genes(self, weights: np.ndarray) -> np.ndarray:
        """(n_faces, n_genes) genes of faces given by full weights (shapes first)."""
        w = np.atleast_2d(np.asarray(weights, dtype=np.float64))[:, : len(self.rig.shape_names)]
        return self.rig.contract(w, self.eye_motion)

    def distances(
        self, weights: np.ndarray, emotion: str, motions: Sequence[Any] | None = None
    ) -> np.ndarray:
        """(n_faces,) distances of shown faces to the prototype of ``emotion``: gene ED, or for
        faces that move (``motions``: each face's ``motion`` as the page gets it) the clip
        distance of the module docstring."""
        genes = self.genes(weights)
        proto = self.prototypes[emotion]
        if motions is None or all(m is None for m in motions):
            return np.asarray(np.linalg.norm(genes - proto, axis=1))
        if emotion not in self.courses:
            raise ConfigError(f"the simulated participant has no time course of '{emotion}'")
        clip_s = float(motions[0]["clip_s"])
        t = np.linspace(0.0, clip_s, self.design.clip_samples)
        first_shape = np.argmax(self.rig.expansion_matrix(self.eye_motion), axis=1)
        rows = np.stack([np.asarray(m["curves"], dtype=np.float64)[first_shape] for m in motions])
        shown = genes[None, :, :] * _course_at(rows, t)  # (F, faces, genes)
        own = self.courses[emotion]
        mine = np.array([*(own[:3] * clip_s), 3 * own[3], 3 * own[4]])
        c = _course_at(mine, t)
        target = c[:, None] * proto[None, :]  # (F, genes)
        sq = ((shown - target[:, None, :]) ** 2).sum(axis=(0, 2))
        return np.asarray(np.sqrt(sq / max(float(c @ c), 1e-12)))

    def _order(self, distances: np.ndarray, temperature: float) -> np.ndarray:
        """Indices in the order a softmax chooser picks them (Gumbel trick)."""
        if temperature == 0:
            return np.argsort(distances, kind="stable")
        keys = distances / temperature - self.rng.gumbel(size=len(distances))
        return np.argsort(keys, kind="stable")

    def select(
        self,
        weights: np.ndarray,
        emotion: str,
        limits: tuple[int, int],
        motions: Sequence[Any] | None = None,
    ) -> tuple[int, list[int]]:
        """(elite position, other positions) among the shown faces (``motions``: as for
        :meth:`distances`)."""
        d = self.distances(weights, emotion, motions)
        lo, hi = limits
        n = int(np.clip(self.design.n_selected, lo, hi))
        order = self._order(d, self.design.select_noise)[:n]
        return int(order[0]), [int(i) for i in order[1:]]

    def rate(self, weights: np.ndarray, emotion: str, points: int, motion: Any = None) -> int:
        """How well the final face shows the emotion: 1 … points (closer: higher)."""
        proto = self.prototypes[emotion]
        d = float(self.distances(weights, emotion, None if motion is None else [motion])[0])
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
