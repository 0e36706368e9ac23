"""Test–retest reliability of the faces participants make (Carlisi et al. 2021, R. Soc. Open
Sci. 8:202251, made each emotion repeatedly): does a participant make the same face again?

For one emotion on one identity, participant i made k_i ≥ 1 final faces x_ij. In a space where
faces are points and distances Euclidean, the one-way random-effects model
x_ij = μ + b_i + e_ij (Cov b = Σ_b, Cov e = Σ_w) has, summed over the space's dimensions,

* within-person variance σ²_w = tr Σ_w: E d²(x_ij, x_ij′) = 2 σ²_w;
* between-person variance σ²_b = tr Σ_b: E d²(x_ij, x_i′j′) = 2 (σ²_b + σ²_w);

and the intraclass correlation ICC = σ²_b / (σ²_b + σ²_w) = 1 − E d²_within / E d²_between:
the share of the faces' variance that is the person (ICC(1) of Shrout & Fleiss 1979, on the
trace: the multivariate form used for distance-based designs, Anderson 2001). The estimates are
the ANOVA (method-of-moments) ones, written with distances only (Σ_j‖x_ij − x̄_i‖² =
Σ_{j<j′} d²_jj′ / k_i), so they hold for any unbalanced design; they equal, per dimension, the
REML estimates of a random-intercept mixed model when the design is balanced and the estimate
positive (tests/analysis/test_reliability.py checks them against statsmodels' MixedLM).

Spaces (each a Euclidean embedding of a distance EmoGen reports):

* ``ed``: genes (the GA's search space; the paper's ED on unique genes);
* ``cd``: the corrected weight vectors scaled to unit length — for unit vectors ‖u − v‖² = 2·CD,
  so this is the paper's CD (eq. 12);
* ``vertex_rms``: the vertices' displacement from neutral (cm; the paper's eq. 13), shapes and
  correctives blended linearly (eyeballs blended, not rotated), through the Gram matrix of the
  deltas: no vertex is ever evaluated.

**Confidence intervals**: the jackknife over participants (leave one participant out; the
pseudo-values' mean ± t(n − 1) SE; for the ICC on Fisher's z scale): the participant is the
unit. **Split-half**: each
participant's repetitions split into odd and even, the halves' mean faces compared over
participants — the vector correlation r of the two halves' deviations from their grand means,
Spearman–Brown corrected to the full length (2r / (1 + r)), and self-identification (the share
of participants whose one half is nearest their own other half, against chance 1/n, with a
permutation p over participants).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from scipy import stats

from emogen.errors import DataError

if TYPE_CHECKING:
    from emogen.analysis.people import People
    from emogen.model.face import FaceModel

SPACES = ("ed", "cd", "vertex_rms")
SPACE_UNITS = {"ed": "gene units", "cd": "CD", "vertex_rms": "cm"}


@dataclass(frozen=True)
class Components:
    """Variance components of one set of faces (sums over the space's dimensions)."""

    icc: float
    within: float  # σ²_w
    between: float  # σ²_b (the moment estimate: may fall below 0 by chance)
    participants: int
    faces: int
    k0: float  # the effective number of faces per participant


def features(people: People, space: str, model: FaceModel | None = None) -> np.ndarray:
    """(n_faces, d) every final face as a point of ``space`` (see the module docstring)."""
    if space == "ed":
        return people.gene_matrix()
    w = people.weight_matrix()
    if space == "cd":
        norm = np.linalg.norm(w, axis=1, keepdims=True)
        return np.divide(w, norm, out=np.zeros_like(w), where=norm > 0)
    if space == "vertex_rms":
        if model is None:
            raise DataError("vertex RMS needs the face model")
        return w @ vertex_embedding(model, people.weights)
    raise DataError(f"unknown space '{space}'; use one of {', '.join(SPACES)}")


def vertex_embedding(model: FaceModel, weight_columns: tuple[str, ...]) -> np.ndarray:
    """(n_weights, r) E with ‖(w₁ − w₂) E‖ the vertex RMS (cm) between two linearly blended
    faces: E = U √Λ / √V from the Gram matrix D Dᵀ = U Λ Uᵀ of the shape and corrective deltas
    in the export's ``w_`` column order."""
    from emogen.simulate.problem import make_correction

    corr = make_correction(model)
    names = [f"w_{n}" for n in corr.names]
    if list(weight_columns) != names:
        raise DataError(
            "the export's weight columns are not this model's shapes and correctives "
            f"({len(weight_columns)} columns against {len(names)}): analyse it with the model "
            "the study used"
        )
    v = model.n_vertices
    deltas = np.concatenate(
        [model.deltas.reshape(model.n_shapes, -1), corr.deltas.reshape(len(corr.deltas), -1)]
    ).astype(np.float64)
    lam, u = np.linalg.eigh(deltas @ deltas.T)
    keep = lam > lam.max() * 1e-12
    return np.asarray(u[:, keep] * np.sqrt(lam[keep]) / np.sqrt(v))


def _blocks(x: np.ndarray, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per participant: k_i, the within sum Σ_{j<j′} d², and the (n, n) matrix P of Σ_{j,j′}
    d²(x_ij, x_i′j′) over all face pairs of two participants (P_ii = 2 × the within sum)."""
    sq = np.sum(x * x, axis=1)
    d2 = np.maximum(sq[:, None] + sq[None, :] - 2 * x @ x.T, 0.0)
    n = int(codes.max()) + 1
    member = np.zeros((n, len(codes)))
    member[codes, np.arange(len(codes))] = 1.0
    p = member @ d2 @ member.T
    k = member.sum(axis=1)
    return k, np.diag(p) / 2, p


def _components(k: np.ndarray, within: np.ndarray, p: np.ndarray, c: np.ndarray) -> np.ndarray:
    """ICC, σ²_w, σ²_b, k0 for participant multiplicities ``c`` (B, n) — a bootstrap draw
    counts a participant c times as c distinct people."""
    c = np.atleast_2d(c)
    n_people = c.sum(axis=1)
    n_faces = c @ k
    ssw = c @ (within / k)
    sst = np.einsum("bi,ij,bj->b", c, p, c) / (2 * n_faces)
    ssb = sst - ssw
    k0 = (n_faces - (c @ k**2) / n_faces) / (n_people - 1)
    s2w = ssw / (n_faces - n_people)
    s2b = (ssb / (n_people - 1) - s2w) / k0
    with np.errstate(invalid="ignore", divide="ignore"):
        icc = s2b / (s2b + s2w)
    return np.stack([icc, s2w, s2b, k0], axis=1)


def components(x: np.ndarray, participants: np.ndarray) -> Components:
    """Variance components and ICC of faces ``x`` (n_faces, d) by their ``participants``."""
    codes, people = _codes(participants)
    k, within, p = _blocks(np.asarray(x, dtype=np.float64), codes)
    if (k >= 2).sum() < 2:
        raise DataError("reliability needs at least 2 participants with 2 or more faces each")
    icc, s2w, s2b, k0 = _components(k, within, p, np.ones(len(people)))[0]
    return Components(float(icc), float(s2w), float(s2b), len(people), len(x), float(k0))


def _codes(participants: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    people, codes = np.unique(np.asarray(participants).astype(str), return_inverse=True)
    return codes, people


def icc_interval(
    x: np.ndarray, participants: np.ndarray, *, confidence: float = 0.95
) -> tuple[float, float]:
    """Jackknife-t interval of the ICC over participants (Tukey 1958) on Fisher's z scale:
    the leave-one-participant-out pseudo-values of z = ½ log F, F = MS_between / MS_within =
    1 + k0 σ²_b / σ²_w (Fisher 1925: z = ½ log((1 + (k0 − 1) ICC) / (1 − ICC))), their mean ±
    t(n − 1) × their standard error, back to the ICC by ICC = (F − 1) / (F + k0 − 1) (k0 of
    the whole study). Fisher's z because the ICC's sampling distribution is skewed near 0 and
    bounded at 1; the participant bootstrap under-covers in small studies (resampled copies of
    a person look like two people). Where F is 0 or infinite (no spread between or within
    people) the jackknife is on the ICC scale. Coverage (94.6–95.5% over 20 000 studies a
    cell, docs/analysis.md): ``benchmarks/coverage_intervals.py --parts icc``."""
    codes, people = _codes(participants)
    k, within, p = _blocks(np.asarray(x, dtype=np.float64), codes)
    n = len(people)
    whole = _components(k, within, p, np.ones(n))[0]
    leave_one_out = _components(k, within, p, 1.0 - np.eye(n))

    def log_f(c: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.log1p(c[..., 3] * c[..., 2] / c[..., 1]) / 2

    pseudo = n * log_f(whole) - (n - 1) * log_f(leave_one_out)
    if not np.all(np.isfinite(pseudo)):  # no spread within or between people: F is 0 or ∞
        return jackknife_interval(x, participants, "icc", confidence=confidence)
    se = pseudo.std(ddof=1) / np.sqrt(n)
    t = stats.t.ppf((1 + confidence) / 2, n - 1)
    k0 = whole[3]
    f_low, f_high = np.exp(2 * (pseudo.mean() - t * se)), np.exp(2 * (pseudo.mean() + t * se))
    return float((f_low - 1) / (f_low + k0 - 1)), float((f_high - 1) / (f_high + k0 - 1))


def jackknife_interval(
    x: np.ndarray, participants: np.ndarray, which: str, *, confidence: float = 0.95
) -> tuple[float, float]:
    """Jackknife-t interval over participants of one component: ``icc``, ``within`` (σ²_w) or
    ``between`` (σ²_b): the pseudo-values' mean ± t(n − 1) × their standard error."""
    column = ("icc", "within", "between").index(which)
    codes, people = _codes(participants)
    k, within, p = _blocks(np.asarray(x, dtype=np.float64), codes)
    n = len(people)
    theta = _components(k, within, p, np.ones(n))[0, column]
    leave_one_out = _components(k, within, p, 1.0 - np.eye(n))[:, column]
    pseudo = n * theta - (n - 1) * leave_one_out
    se = pseudo.std(ddof=1) / np.sqrt(n)
    t = stats.t.ppf((1 + confidence) / 2, n - 1)
    return float(pseudo.mean() - t * se), float(pseudo.mean() + t * se)


def distances(x: np.ndarray, participants: np.ndarray, space: str = "ed") -> pd.DataFrame:
    """Per participant with ≥ 2 faces: mean distance between their own faces (within) and
    mean distance from their faces to other participants' faces (between), in the space's
    own distance (for ``cd``: CD = d² / 2 of the unit vectors)."""
    codes, people = _codes(participants)
    x = np.asarray(x, dtype=np.float64)
    sq = np.sum(x * x, axis=1)
    d2 = np.maximum(sq[:, None] + sq[None, :] - 2 * x @ x.T, 0.0)
    d = d2 / 2 if space == "cd" else np.sqrt(d2)
    same = codes[:, None] == codes[None, :]
    rows = []
    for i, person in enumerate(people):
        mine = codes == i
        k = int(mine.sum())
        if k < 2:
            continue
        block = d[np.ix_(mine, mine)]
        rows.append(
            {
                "participant_id": person,
                "faces": k,
                "within": float(block[np.triu_indices(k, 1)].mean()),
                "between": float(d[np.ix_(mine, ~same[mine].any(axis=0))].mean()),
            }
        )
    return pd.DataFrame(rows, columns=["participant_id", "faces", "within", "between"])


def split_half(
    x: np.ndarray, participants: np.ndarray, repetition: np.ndarray, *, rng: np.random.Generator
) -> dict[str, float]:
    """Odd against even repetitions (participants with both): vector correlation of the halves'
    mean faces, Spearman–Brown corrected, and self-identification against chance."""
    frame = pd.DataFrame(
        {"p": np.asarray(participants).astype(str), "half": np.asarray(repetition) % 2}
    )
    x = np.asarray(x, dtype=np.float64)
    halves = []
    for h in (0, 1):
        sel = frame["half"].to_numpy() == h
        means = pd.DataFrame(x[sel]).groupby(frame["p"].to_numpy()[sel]).mean()
        halves.append(means)
    both = halves[0].index.intersection(halves[1].index)
    n = len(both)
    if n < 3:
        return {"participants": float(n)}
    a, b = halves[0].loc[both].to_numpy(), halves[1].loc[both].to_numpy()
    ca, cb = a - a.mean(axis=0), b - b.mean(axis=0)
    r = float(np.sum(ca * cb) / np.sqrt(np.sum(ca**2) * np.sum(cb**2)))
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    hits = float(np.mean(np.argmin(d, axis=1) == np.arange(n)))
    perms = np.array(
        [np.mean(np.argmin(d[:, rng.permutation(n)], axis=1) == np.arange(n)) for _ in range(999)]
    )
    return {
        "participants": float(n),
        "r_half": r,
        "spearman_brown": 2 * r / (1 + r),
        "self_identification": hits,
        "chance": 1 / n,
        "p_identification": float((1 + np.sum(perms >= hits)) / 1000),
    }
