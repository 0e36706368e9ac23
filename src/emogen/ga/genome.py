"""What a gene is: a weight (static faces), or a weight with a time course (dynamic faces).

Algorithm 1 (:mod:`emogen.ga.algorithm`) is written once; a genome is the representation of a
gene and the sampling of the operators that make new gene values (M, R, A). Crossover (B)
exchanges whole genes and needs nothing from the genome.

* :data:`STATIC`: a gene is one number in [0, 1], the shape's weight (the paper). Its operators
  are :mod:`emogen.ga.operators`' own, so static runs draw and breed exactly as before.
* :class:`DynamicGenome`: a gene is six numbers in [0, 1] (:data:`PARAMS`): its peak amplitude
  (the static weight) and five temporal parameters after Jack, Garrod, Yu, Caldara & Schyns
  (2012, PNAS 109:7241) — onset latency, acceleration, peak latency, deceleration, offset
  latency — mapped to a closed-form curve over a clip of ``clip_s`` seconds (:func:`curve`;
  docs/ga.md, "Dynamic faces"). Genes are arrays (…, K, 6).

A dynamic gene always carries its timing, also while its amplitude is 0 (it is latent: a
mutation of the amplitude alone brings the gene in with the curve it carries).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from emogen.errors import ConfigError, ShapeError
from emogen.ga.draws import Draws
from emogen.ga.operators import average, mutate, random_faces

#: A dynamic gene's parameters, in column order.
TIMING = ("onset", "acceleration", "peak", "deceleration", "offset")
PARAMS = ("amplitude", *TIMING)


class Genome(Protocol):
    """A gene's representation and the sampling of the operators that make gene values."""

    @property
    def params(self) -> tuple[str, ...] | None:
        """``None`` for one number per gene; else the names of a gene's parameters (last
        axis)."""

    def random(self, n: int, n_genes: int, x: int, draws: Draws) -> np.ndarray: ...

    def mutate(self, genes: np.ndarray, m: int, draws: Draws) -> np.ndarray: ...

    def average(self, members: np.ndarray) -> np.ndarray: ...

    def amplitude(self, genes: np.ndarray) -> np.ndarray: ...

    def extra_draws(self, n_genes: int, mutation_genes: int) -> int: ...

    def initial(self, amplitudes: np.ndarray, rng: np.random.Generator) -> np.ndarray: ...

    def to_dict(self) -> dict[str, Any] | None: ...


class StaticGenome:
    """A gene is its weight: the paper's operators R, M, A unchanged."""

    params = None

    def random(self, n: int, n_genes: int, x: int, draws: Draws) -> np.ndarray:
        return random_faces(n, n_genes, x, draws)

    def mutate(self, genes: np.ndarray, m: int, draws: Draws) -> np.ndarray:
        return mutate(genes, m, draws)

    def average(self, members: np.ndarray) -> np.ndarray:
        return average(members)

    def amplitude(self, genes: np.ndarray) -> np.ndarray:
        return np.asarray(genes, dtype=np.float64)

    def extra_draws(self, n_genes: int, mutation_genes: int) -> int:
        return 0

    def initial(self, amplitudes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return amplitudes

    def to_dict(self) -> None:
        """Nothing is recorded for a static genome (states as before dynamic faces)."""
        return None


STATIC = StaticGenome()


@dataclass(frozen=True)
class DynamicGenome:
    """Genes with a time course over a clip of ``clip_s`` seconds, then ``hold_s`` at rest.

    ``min_segment_s``: the shortest rise or fall (also the least time left after the onset), so
    that no curve jumps. ``keyframes``: the times, evenly over the clip, at which a face's
    correctives are computed (:mod:`emogen.ga.motion`; between them they are interpolated). The
    page loops clip + hold; :func:`frame_times` gives the frames.
    """

    clip_s: float = 1.25
    hold_s: float = 0.75
    min_segment_s: float = 0.08
    keyframes: int = 21

    params = PARAMS

    def __post_init__(self) -> None:
        for name in ("clip_s", "hold_s", "min_segment_s"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ConfigError(f"dynamic {name} must be a number of seconds; got {value!r}")
        if not 0.2 <= self.clip_s <= 10:
            raise ConfigError(f"dynamic clip_s must be in [0.2, 10] seconds; got {self.clip_s}")
        if not 0 <= self.hold_s <= 10:
            raise ConfigError(f"dynamic hold_s must be in [0, 10] seconds; got {self.hold_s}")
        if (
            isinstance(self.keyframes, bool)
            or not isinstance(self.keyframes, int)
            or not 2 <= self.keyframes <= 200
        ):
            raise ConfigError(
                f"dynamic keyframes must be an integer in [2, 200]; got {self.keyframes!r}"
            )
        if not 0 < self.min_segment_s <= self.clip_s / 4:
            raise ConfigError(
                f"dynamic min_segment_s must be in (0, clip_s / 4 = {self.clip_s / 4}]; got "
                f"{self.min_segment_s}"
            )

    # ---- the operators' sampling ----------------------------------------------------------
    def random(self, n: int, n_genes: int, x: int, draws: Draws) -> np.ndarray:
        """R(x): amplitudes as the static R (same draws first), then every gene's timing
        U(0, 1)^5 (``uniforms((n, K, 5))``). Returns (R, n, K, 6)."""
        amp = random_faces(n, n_genes, x, draws)
        timing = draws.uniforms((n, n_genes, len(TIMING)))
        return np.concatenate([amp[..., None], timing], axis=-1)

    def mutate(self, genes: np.ndarray, m: int, draws: Draws) -> np.ndarray:
        """M({i}_m) on (R, M, K, 6) genes: per mutation j a gene index U{0..K−1}, a new amplitude
        U(0, 1), a coin and a new timing U(0, 1)^5; the coin (< ½) sets the amplitude, else the
        timing (all five). Draws: ``integers(K, (M, m))``, ``uniforms((M, m))`` (amplitudes),
        ``uniforms((M, m))`` (coins), ``uniforms((M, m, 5))``. Later j wins on a repeat."""
        genes = _genes(genes, 4)
        if m < 0:
            raise ShapeError(f"mutation_genes (m) must be >= 0; got {m}")
        out = genes.copy()
        r, n, k, _ = genes.shape
        if not (m and k):
            return out
        index = draws.integers(k, (n, m))
        amp = draws.uniforms((n, m))
        coin = draws.uniforms((n, m))
        timing = draws.uniforms((n, m, len(TIMING)))
        runs, faces = np.meshgrid(np.arange(r), np.arange(n), indexing="ij")
        for j in range(m):
            at = (runs, faces, index[:, :, j])
            gene = out[at]
            gene = np.where(
                (coin[:, :, j] < 0.5)[..., None],
                np.concatenate([amp[:, :, j, None], gene[..., 1:]], axis=-1),
                np.concatenate([gene[..., :1], timing[:, :, j]], axis=-1),
            )
            out[at] = gene
        return out

    def average(self, members: np.ndarray) -> np.ndarray:
        """A on (R, S, K, 6): the mean amplitude; each timing parameter the mean weighted by the
        members' amplitudes of that gene (the plain mean where every amplitude is 0), so the
        average's curve comes from the faces that show the gene."""
        members = _genes(members, 4)
        if members.shape[1] == 0:
            raise ShapeError("average needs at least one face; got 0")
        amp = members[..., 0]
        total = amp.sum(axis=1)
        weights = np.where(total[:, None] > 0, amp, 1.0)
        timing = (weights[..., None] * members[..., 1:]).sum(axis=1) / weights.sum(axis=1)[
            ..., None
        ]
        return np.concatenate([amp.mean(axis=1)[..., None], timing], axis=-1)

    def amplitude(self, genes: np.ndarray) -> np.ndarray:
        return np.asarray(genes, dtype=np.float64)[..., 0]

    def extra_draws(self, n_genes: int, mutation_genes: int) -> int:
        """Doubles per face beyond the static block: mutation coins and timings, random timing."""
        return mutation_genes * (1 + len(TIMING)) + n_genes * len(TIMING)

    def initial(self, amplitudes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Generation 0 from its static amplitudes (N, K): every gene's timing U(0, 1)^5, drawn
        after the static initialisation from the same generator."""
        amplitudes = np.asarray(amplitudes, dtype=np.float64)
        timing = rng.random((*amplitudes.shape, len(TIMING)))
        return np.concatenate([amplitudes[..., None], timing], axis=-1)

    # ---- the curve ------------------------------------------------------------------------
    def times(self, genes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(onset, peak, offset) latencies in seconds of (…, 6) genes."""
        return latencies(
            np.asarray(genes, dtype=np.float64)[..., 1:], self.clip_s, self.min_segment_s
        )

    def weights_at(self, genes: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Gene weights at times ``t`` (F,) seconds: (…, K, 6) genes → (…, F, K)."""
        genes = np.asarray(genes, dtype=np.float64)
        timing = genes[..., 1:]
        shape = curve(
            timing[..., None, :, :],
            np.asarray(t, dtype=np.float64)[:, None],
            self.clip_s,
            self.min_segment_s,
        )
        out: np.ndarray = genes[..., None, :, 0] * shape
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": "dynamic",
            "clip_s": self.clip_s,
            "hold_s": self.hold_s,
            "min_segment_s": self.min_segment_s,
            "keyframes": self.keyframes,
        }


def _genes(genes: np.ndarray, ndim: int) -> np.ndarray:
    genes = np.asarray(genes, dtype=np.float64)
    if genes.ndim != ndim or genes.shape[-1] != len(PARAMS):
        raise ShapeError(
            f"dynamic genes must have shape (n_runs, n_faces, n_genes, {len(PARAMS)}); got "
            f"{genes.shape}"
        )
    return genes


def latencies(
    timing: np.ndarray, clip_s: float, min_segment_s: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Onset, peak and offset latencies (s) of timing parameters (…, 5) in [0, 1].

    With D = ``clip_s`` and δ = ``min_segment_s`` (stick-breaking, so any values in [0, 1]
    give 0 ≤ t_on, t_on + δ ≤ t_peak ≤ D − δ, t_peak + δ ≤ t_off ≤ D):
    t_on = o (D − 2δ); t_peak = t_on + δ + p (D − 2δ − t_on); t_off = t_peak + δ + f (D − δ − t_peak).
    """
    o, p, f = timing[..., 0], timing[..., 2], timing[..., 4]
    d, s = clip_s, min_segment_s
    t_on = o * (d - 2 * s)
    t_peak = t_on + s + p * (d - 2 * s - t_on)
    t_off = t_peak + s + f * (d - s - t_peak)
    return t_on, t_peak, t_off


def hermite(x: np.ndarray, slope: np.ndarray) -> np.ndarray:
    """H(x; m) = 3x² − 2x³ + m(x³ − 2x² + x): from 0 (slope m) to 1 (slope 0), monotone and in
    [0, 1] for x, m in [0, 1] × [0, 3]."""
    out: np.ndarray = 3 * x**2 - 2 * x**3 + slope * (x**3 - 2 * x**2 + x)
    return out


def curve(timing: np.ndarray, t: np.ndarray, clip_s: float, min_segment_s: float) -> np.ndarray:
    """The time course in [0, 1] of genes with timing (…, 5) at times ``t`` (broadcast).

    0 before the onset and from the offset; rising H((t − t_on)/(t_peak − t_on); 3·acceleration)
    to 1 at the peak; falling H((t_off − t)/(t_off − t_peak); 3·deceleration) back to 0.
    Acceleration (deceleration) is how abruptly the action starts (ends): 0 from (into) rest,
    1 at full speed. Continuous everywhere, smooth at the peak.
    """
    t_on, t_peak, t_off = latencies(timing, clip_s, min_segment_s)
    return course(t_on, t_peak, t_off, 3 * timing[..., 1], 3 * timing[..., 3], t)


def course(
    t_on: np.ndarray,
    t_peak: np.ndarray,
    t_off: np.ndarray,
    up: np.ndarray,
    down: np.ndarray,
    t: np.ndarray,
) -> np.ndarray:
    """:func:`curve` from its latencies (s, t_on < t_peak < t_off) and its Hermite slopes
    ``up`` = 3·acceleration and ``down`` = 3·deceleration (the rows the page is sent,
    :func:`emogen.ga.motion.shape_curves`), at times ``t`` (broadcast)."""
    rise = np.clip((t - t_on) / (t_peak - t_on), 0.0, 1.0)
    fall = np.clip((t_off - t) / (t_off - t_peak), 0.0, 1.0)
    out: np.ndarray = np.where(t <= t_peak, hermite(rise, up), hermite(fall, down))
    return out


def genome_of(spec: dict[str, Any] | None) -> Genome:
    """The genome a state records (``None``: static)."""
    if spec is None:
        return STATIC
    if not isinstance(spec, dict) or spec.get("kind") != "dynamic":
        raise ConfigError(f"genome must be null or {{kind = 'dynamic', …}}; got {spec!r}")
    rest = {k: v for k, v in spec.items() if k != "kind"}
    unknown = sorted(set(rest) - {"clip_s", "hold_s", "min_segment_s", "keyframes"})
    if unknown:
        raise ConfigError(f"dynamic genome: unknown key(s) {unknown}")
    return DynamicGenome(**rest)


def keyframe_times(genome: DynamicGenome) -> np.ndarray:
    """The times (s) at which faces are corrected: ``keyframes`` evenly over [0, clip_s]."""
    return np.linspace(0.0, genome.clip_s, genome.keyframes)


def frame_times(genome: DynamicGenome, fps: float) -> np.ndarray:
    """Times (s) of the clip's frames at ``fps``: 0, 1/fps, …, clip_s (the last frame at the
    clip's end, where every curve is back at 0)."""
    if not 1 <= fps <= 240:
        raise ConfigError(f"fps must be in [1, 240]; got {fps}")
    n = int(np.ceil(genome.clip_s * fps - 1e-9))
    return np.linspace(0.0, genome.clip_s, n + 1)
