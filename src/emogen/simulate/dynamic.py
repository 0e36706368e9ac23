"""Simulated observers of dynamic faces: targets that move, and what the observer compares.

A dynamic simulation (``SimulationConfig.dynamic``) evolves genes (R, N, K, 6) with the same
Algorithm 1 as a static one (:func:`emogen.ga.algorithm.next_generation`, given the genome).
Its target is a dynamic face: the static target's amplitudes per gene and a timing per gene.
Every shown face is measured against it by the three distances of
:mod:`emogen.metrics.dynamic`; the observer ranks by the total (CD over the trajectory), with the
static observer's choice noise (:func:`emogen.simulate.observer.choice_order`).

With ``hold_timing`` the GA evolves amplitudes only (:class:`HeldTiming`): every gene keeps the
target's timing, so its operators are the static ones and draw exactly as a static run does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from emogen.config import DynamicSimulationConfig
from emogen.errors import ConfigError
from emogen.ga.draws import Draws
from emogen.ga.genome import PARAMS, STATIC, DynamicGenome
from emogen.metrics import cosine_distance
from emogen.metrics.dynamic import timing_distance, trajectory_cd
from emogen.model.rig import Rig


def sample_times(genome: DynamicGenome, samples: int) -> np.ndarray:
    """``samples`` (≥ 2) times (s) evenly over [0, clip_s], the clip's ends included."""
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 2:
        raise ConfigError(f"a trajectory needs at least 2 time samples; got {samples!r}")
    return np.linspace(0.0, genome.clip_s, samples)


def trajectory(
    genome: DynamicGenome, genes: np.ndarray, expansion: np.ndarray, times: np.ndarray
) -> np.ndarray:
    """Full weights of faces (…, K, 6) at ``times`` (T,): (…, T, S), with the rig's 0/1
    expansion (K, S) (:meth:`emogen.model.rig.Rig.expansion_matrix`)."""
    out: np.ndarray = genome.weights_at(genes, times) @ np.asarray(expansion, dtype=np.float64)
    return out


def latencies(genome: DynamicGenome, genes: np.ndarray) -> np.ndarray:
    """Onset, peak and offset latencies (s) of faces (…, K, 6): (…, K, 3)."""
    return np.stack(genome.times(genes), axis=-1)


def genome_of_config(config: DynamicSimulationConfig) -> DynamicGenome:
    """The genome of a dynamic simulation config (its clip and segment settings)."""
    return DynamicGenome(
        clip_s=config.clip_s, hold_s=config.hold_s, min_segment_s=config.min_segment_s
    )


@dataclass(frozen=True, eq=False)
class HeldTiming:
    """Dynamic genes whose timing is fixed: (K, 5) ``timing``; R, M, A on amplitudes are the
    static operators (same draws), so a run differs from a static one only in what it shows."""

    dynamic: DynamicGenome
    timing: np.ndarray

    params = PARAMS

    def _with_timing(self, amplitudes: np.ndarray) -> np.ndarray:
        timing = np.broadcast_to(self.timing, (*amplitudes.shape, self.timing.shape[-1]))
        return np.concatenate([amplitudes[..., None], timing], axis=-1)

    def random(self, n: int, n_genes: int, x: int, draws: Draws) -> np.ndarray:
        return self._with_timing(STATIC.random(n, n_genes, x, draws))

    def mutate(self, genes: np.ndarray, m: int, draws: Draws) -> np.ndarray:
        return self._with_timing(STATIC.mutate(np.asarray(genes)[..., 0], m, draws))

    def average(self, members: np.ndarray) -> np.ndarray:
        return self._with_timing(STATIC.average(np.asarray(members)[..., 0]))

    def amplitude(self, genes: np.ndarray) -> np.ndarray:
        return np.asarray(genes, dtype=np.float64)[..., 0]

    def extra_draws(self, n_genes: int, mutation_genes: int) -> int:
        return 0

    def initial(self, amplitudes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return self._with_timing(np.asarray(amplitudes, dtype=np.float64))

    def to_dict(self) -> dict[str, Any]:
        return {**self.dynamic.to_dict(), "held_timing": self.timing.tolist()}


def target_genes(
    config: DynamicSimulationConfig, rig: Rig, weights: np.ndarray, eye_motion: bool
) -> np.ndarray:
    """The dynamic target (K, 6): the target's weights per gene, with the configured timing.

    Every gene with a non-zero weight needs its timing; a timing for a gene the target does not
    show, or for a name that is no gene, is an error (it would be silently unused). A gene the
    target does not show gets the amplitude-weighted mean timing of those it shows (what
    :meth:`DynamicGenome.average` gives a gene; only held timing ever shows it).
    """
    names = rig.gene_names(eye_motion)
    amp = rig.contract(np.asarray(weights, dtype=np.float64)[None], eye_motion)[0]
    expanded = rig.expand(amp[None], eye_motion)[0]
    if not np.allclose(expanded, weights, atol=1e-12):
        raise ConfigError(
            "a dynamic target is given per gene: both shapes of a pair (e.g. mouthSmile_L and "
            "mouthSmile_R) must have the same weight, and excluded shapes none"
        )
    unknown = sorted(set(config.timing) - set(names))
    if unknown:
        raise ConfigError(f"dynamic.timing: {unknown} are not genes of the rig '{rig.name}'")
    shown = [names[k] for k in np.flatnonzero(amp > 0)]
    missing = [n for n in shown if n not in config.timing]
    unused = sorted(n for n in config.timing if n not in shown)
    if missing:
        raise ConfigError(
            f"dynamic.timing needs [onset, acceleration, peak, deceleration, offset] for every "
            f"gene of the target; missing for {missing}"
        )
    if unused:
        raise ConfigError(f"dynamic.timing: {unused} have weight 0 in the target")
    timing = np.empty((len(names), len(PARAMS) - 1))
    for k, name in enumerate(names):
        if name in config.timing:
            timing[k] = config.timing[name]
    on = amp > 0
    timing[~on] = (amp[on, None] * timing[on]).sum(axis=0) / amp[on].sum()
    return np.concatenate([amp[:, None], timing], axis=1)


@dataclass(frozen=True, eq=False)
class DynamicView:
    """What a dynamic simulation compares: faces' genes against the target's, three ways."""

    genome: DynamicGenome
    target: np.ndarray  # (K, 6)
    expansion: np.ndarray  # (K, S)
    samples: int

    @property
    def times(self) -> np.ndarray:
        return sample_times(self.genome, self.samples)

    def distance(self, genes: np.ndarray, target: np.ndarray) -> np.ndarray:
        """The observer's metric: CD over the trajectory of faces (…, K, 6) to ``target``."""
        times = self.times
        return trajectory_cd(
            trajectory(self.genome, genes, self.expansion, times),
            trajectory(self.genome, target, self.expansion, times),
        )

    def measure(self, genes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(total, peak, timing) distances of faces (…, K, 6) to the target, each (…)."""
        genes = np.asarray(genes, dtype=np.float64)
        e = self.expansion
        timing = timing_distance(
            latencies(self.genome, genes),
            genes[..., 0],
            latencies(self.genome, self.target),
            self.target[:, 0],
        )
        peak = cosine_distance(genes[..., 0] @ e, self.target[:, 0] @ e)
        return self.distance(genes, self.target), peak, timing


def dynamic_view(
    config: DynamicSimulationConfig, rig: Rig, weights: np.ndarray, eye_motion: bool
) -> DynamicView:
    """The view of a config's dynamic target (``weights``: its full weights (S,))."""
    return DynamicView(
        genome_of_config(config),
        target_genes(config, rig, weights, eye_motion),
        rig.expansion_matrix(eye_motion),
        config.samples,
    )
