"""A dynamic face's clip as frames: the one path from a face's curves to rendered frames, used
by ``emogen render clip`` and by the report's animated prototypes
(:mod:`emogen.tasks.evolve.dynamic_prototypes`).

Frame k is the face at k / fps seconds, up to the first frame at or after the clip's end (the
face at rest), then the hold at rest — so a frame shown 1/fps seconds plays the clip in real
time, looped as the study page loops it. A gene's weight at time t is docs/ga.md's curve
("Dynamic faces"); each frame is rendered as a still face (corrected: each on its own, as the
server's strips).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.errors import ConfigError
from emogen.ga.genome import DynamicGenome
from emogen.ga.motion import core_at

if TYPE_CHECKING:
    import pandas as pd

    from emogen.model.rig import Rig


def clip_genome(
    rows: pd.DataFrame, genes: np.ndarray, clip_s: float | None, hold_s: float, min_segment_s: float
) -> DynamicGenome:
    """The genome of a face's clip: ``clip_s`` from its rows (an export's ``clip_s``) or the
    argument; the rows' latencies (``onset_s``, ``peak_s``, ``offset_s``), when there, must be
    the curve's under ``min_segment_s`` (a study's other ``min_segment_s`` is a wrong clip).
    ``rows``: the face's rows with ``gene_index`` (their row of ``genes`` (K, 6))."""
    if "clip_s" in rows.columns:
        lengths = sorted(set(rows.clip_s.dropna().astype(float)))
        if len(lengths) != 1:
            raise ConfigError(
                f"the face's rows give clip_s {lengths}; one face has one clip length"
            )
        if clip_s is not None and abs(clip_s - lengths[0]) > 1e-9:
            raise ConfigError(f"--clip-s {clip_s} differs from the face's clip_s {lengths[0]}")
        clip_s = lengths[0]
    genome = DynamicGenome(
        clip_s=1.25 if clip_s is None else clip_s, hold_s=hold_s, min_segment_s=min_segment_s
    )
    if {"onset_s", "peak_s", "offset_s"} <= set(rows.columns):
        shown = rows[rows.amplitude > 0]
        got = np.stack(genome.times(genes[shown.gene_index.to_numpy()]), axis=1)
        want = shown[["onset_s", "peak_s", "offset_s"]].to_numpy(float)
        if not np.allclose(got, want, rtol=0, atol=1e-6):
            raise ConfigError(
                f"the face's onset_s/peak_s/offset_s are not its curves' under --min-segment-s "
                f"{min_segment_s}: give the study's min_segment_s (docs/ga.md)"
            )
    return genome


def clip_times(genome: DynamicGenome, fps: float, hold: bool) -> np.ndarray:
    """The clip's frame times (T,): k / fps up to the first frame at or after ``clip_s``, then
    (``hold``) ``round(hold_s · fps)`` frames of the hold at rest."""
    if not 1 <= fps <= 240:
        raise ConfigError(f"--fps must be in [1, 240]; got {fps}")
    rest = round(genome.hold_s * fps) if hold else 0
    return np.arange(int(np.ceil(genome.clip_s * fps - 1e-9)) + 1 + rest) / fps


def clip_weights(
    rig: Rig, genes: np.ndarray, genome: DynamicGenome, t: np.ndarray, eye_motion: bool = True
) -> np.ndarray:
    """Shape weights (…, T, S) of faces' genes (…, K, 6) at times ``t`` (T,)."""
    g = np.asarray(genes, dtype=np.float64)
    flat = g.reshape(-1, *g.shape[-2:])
    w = core_at(genome, flat, t, lambda x: rig.expand(x, eye_motion))
    return w.reshape(*g.shape[:-2], *w.shape[1:])


def render_frames(renderer: Any, weights: np.ndarray, correct: bool) -> np.ndarray:
    """Images (…, H, W, 3) of frames' weights (…, S); a frame equal to another (the face at
    rest) is rendered once."""
    w = np.asarray(weights)
    unique, where = np.unique(w.reshape(-1, w.shape[-1]), axis=0, return_inverse=True)
    images: np.ndarray = renderer.render(unique, correct=correct)
    return images[where.reshape(-1)].reshape(*w.shape[:-1], *images.shape[1:])
