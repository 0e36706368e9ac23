"""Dynamic faces over time: correctives at keyframes, and the weights shown at any time.

A dynamic face (:class:`emogen.ga.genome.DynamicGenome`) is corrected at the genome's
``keyframes`` times, evenly over the clip (default 21: every 62.5 ms of 1.25 s), with the
engine's corrector — the same combinational + collision correction a static face gets, called
through its entry point on the batch of every face's keyframes. What is shown at time t
(:func:`frames`) is the core weights of the closed-form curve at t, exactly, with the corrective
weights interpolated linearly between the two keyframes around t. docs/ga.md ("Correctives over
time") gives the measured interpenetration between keyframes (benchmarks/bench_motion.py).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from emogen.ga.genome import DynamicGenome, keyframe_times, latencies

#: (n, K) genes → (n, S) full weight vectors: the rig's expansion of amplitudes at one time.
Expand = Callable[[np.ndarray], np.ndarray]
#: (B, S) weights → (corrective names, (B, C) corrective weights).
Correct = Callable[[np.ndarray], tuple[tuple[str, ...], np.ndarray]]


def core_at(genome: DynamicGenome, genes: np.ndarray, t: np.ndarray, expand: Expand) -> np.ndarray:
    """Core shape weights of faces (n, K, 6) at times ``t`` (T,): (n, T, S)."""
    gene_w = genome.weights_at(genes, np.asarray(t, dtype=np.float64))  # (n, T, K)
    n, steps, k = gene_w.shape
    return expand(gene_w.reshape(n * steps, k)).reshape(n, steps, -1)


def correct_keyframes(
    genome: DynamicGenome, genes: np.ndarray, expand: Expand, correct: Correct
) -> tuple[tuple[str, ...], np.ndarray]:
    """Corrective weights of faces (n, K, 6) at the genome's keyframes: (names, (n, F, C))."""
    core = core_at(genome, genes, keyframe_times(genome), expand)
    n, f, s = core.shape
    # a face's correction is its own (tests/correct): identical keyframes (the face at rest
    # before its first onset and after its last offset) are corrected once
    distinct, where = _distinct(core.reshape(n * f, s))
    names, values = correct(distinct)
    keyed = np.asarray(values, dtype=np.float64)[where]
    return names, keyed.reshape(n, f, -1)


def _distinct(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``rows`` (N, S) in order of first appearance, and each row's index
    among them: (D, S), (N,). Rows are equal when their bytes are (a dict of them: 0.15 ms for
    a population's 210 keyframes, where ``np.unique(axis=0)``'s sort took 1.4 ms a step)."""
    index: dict[bytes, int] = {}
    first: list[int] = []
    where = np.empty(len(rows), dtype=np.int64)
    for i, row in enumerate(np.ascontiguousarray(rows)):
        where[i] = index.setdefault(row.tobytes(), len(index))
        if where[i] == len(first):
            first.append(i)
    return rows[first], where


def interpolate(genome: DynamicGenome, keyed: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Values at keyframes (n, F, C) at times ``t`` (T,), linearly between keyframes (held
    before the first and after the last): (n, T, C)."""
    key_t = keyframe_times(genome)
    t = np.clip(np.asarray(t, dtype=np.float64), key_t[0], key_t[-1])
    right = np.clip(np.searchsorted(key_t, t, side="right"), 1, len(key_t) - 1)
    left = right - 1
    s = (t - key_t[left]) / (key_t[right] - key_t[left])
    out: np.ndarray = keyed[:, left] + (keyed[:, right] - keyed[:, left]) * s[None, :, None]
    return out


def frames(
    genome: DynamicGenome,
    genes: np.ndarray,
    keyframe_correctives: np.ndarray | None,
    t: np.ndarray,
    expand: Expand,
) -> np.ndarray:
    """The full weights shown at times ``t``: core weights (exact), then the correctives
    interpolated between keyframes (none for faces shown uncorrected): (n, T, S [+ C])."""
    core = core_at(genome, genes, t, expand)
    if keyframe_correctives is None:
        return core
    return np.concatenate([core, interpolate(genome, keyframe_correctives, t)], axis=-1)


def shape_curves(genome: DynamicGenome, timing: np.ndarray, expansion: np.ndarray) -> np.ndarray:
    """Each shape's curve as the page evaluates it: genes' timing (…, K, 5) and the rig's 0/1
    expansion (K, S) → (…, S, 5) rows ``[t_on, t_peak, t_off, 3·acceleration,
    3·deceleration]`` (seconds, then the Hermite slopes of :func:`emogen.ga.genome.curve`);
    a shape no gene moves gets zeros (its weight is 0 at every time)."""
    timing = np.asarray(timing, dtype=np.float64)
    t_on, t_peak, t_off = latencies(timing, genome.clip_s, genome.min_segment_s)
    rows = np.stack([t_on, t_peak, t_off, 3 * timing[..., 1], 3 * timing[..., 3]], axis=-1)
    moved = expansion.sum(axis=0) > 0
    out: np.ndarray = np.where(moved[:, None], rows[..., np.argmax(expansion, axis=0), :], 0.0)
    return out


#: Frames of a strip (the server's image of a face that moves, for browsers without WebGL).
STRIP_FRAMES = 11


def strip_times(genome: DynamicGenome) -> np.ndarray:
    """The times (s) of a strip's frames: :data:`STRIP_FRAMES` evenly over the clip (every
    125 ms of the default 1.25 s; the last at rest)."""
    return np.linspace(0.0, genome.clip_s, STRIP_FRAMES)
