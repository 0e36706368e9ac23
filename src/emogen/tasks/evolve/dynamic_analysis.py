"""What participants' dynamic faces show about timing: per emotion each gene's temporal profile
across participants, and whether timing differs between emotions.

The participant is the unit: a participant's value for an emotion is the mean over their final
faces of that emotion (``final_faces`` joined with their rows in ``face_curves``). A face's
timing is that of its motion as shown: its energy E(t) = Σ_gene w(t)² (each shown gene's
weight over the clip, :func:`face_motion`); its peak latency is when E is greatest, its onset
and offset the first and last times E reaches ``ENVELOPE`` of that. (Weighting the genes'
own peak latencies by their amplitudes instead flagged shared timing as different in a
simulated null study: the GA leaves brief, late curves on genes the prototype does not move,
and how many depends on the emotion; motion energy counts them by how much they show.)
Intervals are percentile bootstraps over participants.

The timing test (per block with dynamic faces, on participants who finished every emotion of
it): the repeated-measures F of the participants' peak latencies by emotion, its p-value from
permuting the emotion labels within each participant (exchangeable when timing does not depend
on the emotion; ``PERMUTATIONS`` permutations, p = (1 + #{F* ≥ F}) / (1 + B)), and its effect
size, partial η² = SS_emotion / (SS_emotion + SS_error), with a bootstrap interval over
participants.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from emogen.ga.genome import course

#: Bootstrap resamples of every interval; permutations of the timing test.
BOOTSTRAP = 2000
PERMUTATIONS = 2000
#: A face's latencies summarised per participant; the sampling step of its motion (s) and the
#: share of its peak motion energy at which it counts as moving.
LATENCIES = ("onset_s", "peak_s", "offset_s")
STEP_S = 0.01
ENVELOPE = 0.1
_JOIN = ["session_id", "trial", "attempt", "generation", "face_id"]


def final_curves(final_faces: pd.DataFrame, face_curves: pd.DataFrame) -> pd.DataFrame:
    """The ``face_curves`` rows of every final face (one row per final face per shown gene),
    with the final face's participant, block name and emotion (and its block's position and
    identity, where the export has them)."""
    extra = [c for c in ("block", "identity") if c in final_faces.columns]
    keys = final_faces[[*_JOIN, "participant_id", "block_name", "emotion", *extra]]
    curves = face_curves.drop(columns=["participant_id"], errors="ignore")
    return curves.merge(keys, on=_JOIN, how="inner")


def face_motion(rows: pd.DataFrame, step_s: float = STEP_S) -> tuple[np.ndarray, np.ndarray]:
    """One face's motion energy E(t) = Σ_gene w(t)² over its clip, sampled every ``step_s``:
    (times, energy); w(t) is each shown gene's amplitude times its curve (docs/ga.md) from its
    row's latencies and slopes."""
    clip_s = float(rows["clip_s"].iloc[0])
    t = np.linspace(0.0, clip_s, round(clip_s / step_s) + 1)
    used = ("amplitude", "acceleration", "deceleration", *LATENCIES)
    col = {c: rows[c].to_numpy(dtype=np.float64)[:, None] for c in used}
    shape = course(
        col["onset_s"],
        col["peak_s"],
        col["offset_s"],
        3 * col["acceleration"],
        3 * col["deceleration"],
        t[None, :],
    )
    return t, ((col["amplitude"] * shape) ** 2).sum(axis=0)


def participant_timing(curves: pd.DataFrame) -> pd.DataFrame:
    """One row per participant, block and emotion: the latencies of their final faces (each
    face's, then the mean over the participant's faces; :data:`LATENCIES`) and how many."""
    keys = ["participant_id", "block_name", "emotion", "session_id", "trial"]
    faces = []
    for key, rows in curves.groupby(keys, sort=True):
        t, energy = face_motion(rows)
        if energy.max() <= 0:
            continue
        moving = t[energy >= ENVELOPE * energy.max()]
        values = (moving[0], t[int(np.argmax(energy))], moving[-1])
        faces.append(
            {**dict(zip(keys, key, strict=True)), **dict(zip(LATENCIES, values, strict=True))}
        )
    per_face = pd.DataFrame(faces, columns=[*keys, *LATENCIES])
    out = per_face.groupby(["participant_id", "block_name", "emotion"], sort=True)
    table = out[list(LATENCIES)].mean()
    table["n_faces"] = out.size()
    return table.reset_index()


def _interval(values: np.ndarray, rng: np.random.Generator, alpha: float) -> tuple[float, float]:
    if len(values) < 2:
        return float("nan"), float("nan")
    boots = values[rng.integers(0, len(values), (BOOTSTRAP, len(values)))].mean(axis=1)
    lo, hi = np.quantile(boots, [alpha / 2, 1 - alpha / 2])
    return float(lo), float(hi)


def emotion_timing(timing: pd.DataFrame, rng: np.random.Generator, alpha: float) -> pd.DataFrame:
    """Per block and emotion: the participants' mean peak latency with its interval."""
    rows = []
    for (block, emotion), g in timing.groupby(["block_name", "emotion"], sort=True):
        peaks = g["peak_s"].to_numpy(dtype=np.float64)
        lo, hi = _interval(peaks, rng, alpha)
        rows.append(
            {
                "block_name": block,
                "emotion": emotion,
                "n_participants": len(peaks),
                "peak_s": float(peaks.mean()),
                "peak_low": lo,
                "peak_high": hi,
                "onset_s": float(g["onset_s"].mean()),
                "offset_s": float(g["offset_s"].mean()),
            }
        )
    return pd.DataFrame(rows)


def gene_profiles(curves: pd.DataFrame, rng: np.random.Generator, alpha: float) -> pd.DataFrame:
    """Per block, emotion and gene: the participants' mean amplitude (0 where their final
    faces do not show the gene) and mean peak latency (of the participants whose faces show it),
    each with its interval over participants."""
    who_keys = ["block_name", "emotion", "participant_id"]
    faces = curves.drop_duplicates([*who_keys, "session_id", "trial"]).groupby(who_keys).size()
    n_faces: dict[Any, int] = {k: int(v) for k, v in faces.items()}
    people: dict[Any, int] = {k: int(v) for k, v in faces.groupby(level=[0, 1]).size().items()}
    per = curves.groupby([*who_keys[:2], "gene", "participant_id"], sort=True).agg(
        amplitude=("amplitude", "sum"), peak_s=("peak_s", "mean")
    )
    rows = []
    for (block, emotion, gene), g in per.groupby(level=[0, 1, 2], sort=True):
        who = g.index.get_level_values("participant_id")
        shown = np.array([n_faces[(block, emotion, p)] for p in who], dtype=np.float64)
        amp = g["amplitude"].to_numpy(dtype=np.float64) / shown
        n = people[(block, emotion)]
        amp = np.concatenate([amp, np.zeros(n - len(amp))])
        peaks = g["peak_s"].to_numpy(dtype=np.float64)
        a_lo, a_hi = _interval(amp, rng, alpha)
        p_lo, p_hi = _interval(peaks, rng, alpha)
        rows.append(
            {
                "block_name": block,
                "emotion": emotion,
                "gene": gene,
                "n_participants": n,
                "n_showing": len(peaks),
                "amplitude": float(amp.mean()),
                "amplitude_low": a_lo,
                "amplitude_high": a_hi,
                "peak_s": float(peaks.mean()),
                "peak_low": p_lo,
                "peak_high": p_hi,
            }
        )
    return pd.DataFrame(rows)


def rm_anova(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Repeated-measures one-way ANOVA of (…, n participants, E emotions): (F, partial η²)."""
    n, e = y.shape[-2:]
    grand = y.mean(axis=(-2, -1), keepdims=True)
    by_emotion = y.mean(axis=-2, keepdims=True)
    by_person = y.mean(axis=-1, keepdims=True)
    ss_emotion = n * ((by_emotion - grand) ** 2).sum(axis=(-2, -1))
    ss_error = ((y - by_emotion - by_person + grand) ** 2).sum(axis=(-2, -1))
    with np.errstate(divide="ignore", invalid="ignore"):  # one person resampled n times
        f = (ss_emotion / (e - 1)) / (ss_error / ((n - 1) * (e - 1)))
        return f, ss_emotion / (ss_emotion + ss_error)


@dataclass(frozen=True)
class TimingTest:
    """Whether the participants' peak latencies differ between a block's emotions."""

    block_name: str
    emotions: tuple[str, ...]
    n_participants: int
    f: float
    p_value: float
    permutations: int
    eta2: float
    eta2_low: float
    eta2_high: float

    def to_dict(self) -> dict[str, object]:
        return {**self.__dict__, "emotions": list(self.emotions)}


def timing_test(
    timing: pd.DataFrame,
    block_name: str,
    rng: np.random.Generator,
    alpha: float,
    permutations: int = PERMUTATIONS,
) -> TimingTest | None:
    """The permutation test of the module docstring on one block (None: fewer than three
    participants with every emotion, or one emotion)."""
    rows = timing[timing["block_name"] == block_name]
    wide = rows.pivot(index="participant_id", columns="emotion", values="peak_s").dropna()
    if wide.shape[1] < 2 or wide.shape[0] < 3:
        return None
    y = wide.to_numpy(dtype=np.float64)
    f, eta2 = rm_anova(y)
    shuffled = rng.permuted(np.broadcast_to(y, (permutations, *y.shape)), axis=2)
    f_null, _ = rm_anova(shuffled)
    boots = y[rng.integers(0, len(y), (BOOTSTRAP, len(y)))]
    _, eta_boot = rm_anova(boots)
    lo, hi = np.nanquantile(eta_boot, [alpha / 2, 1 - alpha / 2])
    return TimingTest(
        block_name=block_name,
        emotions=tuple(str(c) for c in wide.columns),
        n_participants=len(y),
        f=float(f),
        p_value=float((1 + np.sum(f_null >= f)) / (1 + permutations)),
        permutations=permutations,
        eta2=float(eta2),
        eta2_low=float(lo),
        eta2_high=float(hi),
    )
