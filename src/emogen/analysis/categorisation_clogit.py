"""McFadden's conditional logit (the label chosen among the labels offered) and its primary use
in the own-distance model: the pooled fit with participant- and stimulus-level (two-way)
cluster-robust standard errors.

**The fit.** P(answer n chooses label l) = exp(x_nl·β) / Σ_{m offered} exp(x_nm·β) (McFadden
1974), by Newton's method with step halving on the log-likelihood. A fit that cannot give an
estimate says why instead of returning one: a singular information matrix (a predictor that
does not vary among the labels offered, or labels that always co-occur), or estimates running
off to infinity (separation: some choices predicted perfectly), or no convergence in the
allowed iterations. A label nobody chose has its constant at −∞ at the maximum; the primary
fit takes that limit exactly by leaving such labels out of the choice sets (and names them).

**Two-way clustering.** A participant answers many faces, and in a categorise block every face
is shown to many participants: the answers are correlated within participant and within
stimulus (a face that looks angry to one judge looks angry to the next). The covariance is
Cameron, Gelbach & Miller's (2011, *J. Bus. Econ. Stat.* 29:238) two-way cluster-robust
sandwich, V = B (c_P M_P + c_S M_S − c_PS M_PS) B with B the inverse information, M_G the sum
over clusters of G of the outer products of the clusters' summed scores, PS the intersections
(one participant's answers to one face), and c_G = G/(G − 1). Tests and intervals use a t
distribution on min(G_P, G_S) − 1 degrees of freedom (Cameron & Miller 2015, *J. Human
Resources* 50:317). When V's variance of the contrast is not positive (possible: the
subtraction of M_PS), the larger of the two one-way variances is used, and the report says so.

Why not a crossed random-effects GLMM: statsmodels has no maximum-likelihood logistic GLMM with
crossed participant and stimulus effects (its ``BinomialBayesMixedGLM`` is variational Bayes),
a random-effects conditional logit has no implementation in the project's dependencies, and
such fits fail to converge often enough in small studies that the primary test would often be
missing; the sandwich has no variance parameters to converge and is consistent as both
numbers of clusters grow.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

#: Estimates beyond this size (log-odds per unit of a predictor scaled to SD 1) mean separation.
SEPARATION = 50.0


@dataclass(frozen=True, eq=False)
class ClogitFit:
    """A conditional-logit fit: ``beta`` (k,), ``info`` (k, k) the observed information
    (penalised when ridge > 0), ``scores`` (answers, k) each answer's score at ``beta``;
    ``converged`` False with ``reason`` (plain words) when there is no estimate."""

    beta: np.ndarray
    info: np.ndarray
    scores: np.ndarray
    converged: bool
    iterations: int
    reason: str = ""


def _loglik_parts(
    x: np.ndarray, avail: np.ndarray, chosen: np.ndarray, beta: np.ndarray
) -> tuple[float, np.ndarray, np.ndarray]:
    """Log-likelihood, per-answer scores and the information at ``beta``."""
    eta = np.where(avail, x @ beta, -np.inf)
    top = eta.max(axis=1, keepdims=True)
    p = np.exp(eta - top)
    total = p.sum(axis=1, keepdims=True)
    p /= total
    rows = np.arange(len(chosen))
    loglik = float(np.sum(eta[rows, chosen] - top[:, 0] - np.log(total[:, 0])))
    xa = np.where(avail[..., None], x, 0.0)
    mean = np.einsum("nl,nlk->nk", p, xa)
    centred = np.where(avail[..., None], x - mean[:, None, :], 0.0)
    info = np.einsum("nl,nlk,nlj->kj", p, centred, centred)
    return loglik, x[rows, chosen] - mean, info


def conditional_logit(
    x: np.ndarray,
    avail: np.ndarray,
    chosen: np.ndarray,
    ridge: float = 0.0,
    max_iter: int = 100,
) -> ClogitFit:
    """The conditional logit of ``chosen`` (answers,) among ``avail`` (answers, labels) with
    features ``x`` (answers, labels, k), maximised by Newton's method with step halving;
    ``ridge``: a penalty ridge·|β|²/2 on the log-likelihood (0: the maximum-likelihood
    estimate). Never raises on data: a failure is ``converged=False`` with its reason."""
    k = x.shape[2]
    scale = np.array([_spread(x[..., j], avail) for j in range(k)])
    if np.any(scale == 0):
        dead = ", ".join(str(j) for j in np.flatnonzero(scale == 0))
        return _failed(k, 0, f"predictor(s) {dead} do not vary among the labels offered")
    beta = np.zeros(k)
    penalty = ridge * np.eye(k)
    loglik, scores, info = _loglik_parts(x, avail, chosen, beta)
    loglik -= float(ridge * beta @ beta / 2)
    for it in range(1, max_iter + 1):
        info_p = info + penalty
        if not _invertible(info_p):
            return _failed(
                k,
                it,
                "the information matrix is singular (a predictor does not vary within answers, "
                "or predictors are collinear among the labels offered)",
            )
        grad = scores.sum(axis=0) - ridge * beta
        step = np.linalg.solve(info_p, grad)
        for _halving in range(30):
            trial = beta + step
            new, new_scores, new_info = _loglik_parts(x, avail, chosen, trial)
            new -= float(ridge * trial @ trial / 2)
            if new >= loglik - 1e-12 * abs(loglik):
                break
            step = step / 2
        beta, loglik, scores, info = trial, new, new_scores, new_info
        if np.any(np.abs(beta) * scale > SEPARATION):
            return _failed(
                k,
                it,
                "the estimates run off to infinity (separation: the labels are predicted "
                "perfectly by the predictors for some answers or participants)",
            )
        if np.max(np.abs(step) * scale) < 1e-10:
            if not _invertible(info + penalty):
                return _failed(k, it, "the information matrix is singular at the estimate")
            return ClogitFit(beta, info + penalty, scores, True, it)
    return _failed(k, max_iter, f"no convergence in {max_iter} Newton iterations")


def _invertible(info: np.ndarray) -> bool:
    """Whether a symmetric information matrix is safely invertible (condition < 1e10)."""
    eig = np.linalg.eigvalsh(info)
    return bool(np.all(np.isfinite(eig)) and eig[0] > 1e-10 * max(eig[-1], 1e-300))


def _spread(xj: np.ndarray, avail: np.ndarray) -> float:
    """SD of a feature's deviations from its mean over each answer's offered labels."""
    counts = avail.sum(axis=1, keepdims=True)
    mean = np.where(avail, xj, 0.0).sum(axis=1, keepdims=True) / np.maximum(counts, 1)
    dev = np.where(avail, xj - mean, 0.0)
    return float(np.sqrt((dev**2).sum() / max(int(avail.sum()), 1)))


def _failed(k: int, iterations: int, reason: str) -> ClogitFit:
    nan = np.full(k, np.nan)
    return ClogitFit(nan, np.full((k, k), np.nan), np.zeros((0, k)), False, iterations, reason)


def cluster_meat(scores: np.ndarray, clusters: np.ndarray) -> tuple[np.ndarray, int]:
    """Σ over clusters of (summed scores)(summed scores)ᵀ, and the number of clusters."""
    codes, index = np.unique(clusters, return_inverse=True)
    summed = np.zeros((len(codes), scores.shape[1]))
    np.add.at(summed, index, scores)
    return summed.T @ summed, len(codes)


@dataclass(frozen=True)
class Covariance:
    """A two-way cluster-robust covariance: ``cov`` (k, k), the cluster counts, the t
    distribution's degrees of freedom, and ``note`` (non-empty when a fallback was used for the
    contrast ``weights``)."""

    cov: np.ndarray
    n_participants: int
    n_stimuli: int
    df: int
    note: str = ""


def two_way_covariance(
    fit: ClogitFit, participant: np.ndarray, stimulus: np.ndarray, weights: np.ndarray
) -> Covariance:
    """Cameron–Gelbach–Miller two-way covariance of ``fit`` (module docstring). ``weights``
    (m, k): the directions whose variances are used (each slope, the contrast); when any of
    them is not positive in the two-way covariance (possible: M_PS is subtracted), the one-way
    covariance with the larger variance of the last direction (the contrast) is used instead,
    and ``note`` says so."""
    bread = np.linalg.inv(fit.info)
    pairs = np.array([f"{p}\x1f{s}" for p, s in zip(participant, stimulus, strict=True)])
    parts = {}
    for name, ids in (("participant", participant), ("stimulus", stimulus), ("both", pairs)):
        meat, g = cluster_meat(fit.scores, ids)
        parts[name] = (meat * (g / (g - 1) if g > 1 else 1.0), g)
    meat = parts["participant"][0] + parts["stimulus"][0] - parts["both"][0]
    g_p, g_s = parts["participant"][1], parts["stimulus"][1]
    cov = bread @ meat @ bread
    note = ""
    w = np.atleast_2d(weights)
    if not np.all(np.einsum("mk,kj,mj->m", w, cov, w) > 0):
        one_way = [bread @ parts[n][0] @ bread for n in ("participant", "stimulus")]
        cov = max(one_way, key=lambda c: float(w[-1] @ c @ w[-1]))
        note = (
            "the two-way variance of a slope or of the contrast was not positive; the larger "
            "of the participant- and stimulus-clustered covariances is used"
        )
    return Covariance(cov, g_p, g_s, max(min(g_p, g_s) - 1, 1), note)


def table_arrays(
    table: pd.DataFrame, features: tuple[str, ...], constants: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, pd.DataFrame, list[str]]:
    """A long table (answer × offered label) as (answers, labels, k) features (with one
    constant per label but the first, when ``constants``), availability, choices, the answers'
    first rows (for their participant and stimulus) and the labels."""
    labels = sorted(table["label"].unique())
    answers, n_idx = np.unique(table["answer"].to_numpy(), return_inverse=True)
    e_idx = np.searchsorted(labels, table["label"].to_numpy())
    k = len(features) + (len(labels) - 1 if constants else 0)
    x = np.zeros((len(answers), len(labels), k))
    avail = np.zeros((len(answers), len(labels)), dtype=bool)
    x[n_idx, e_idx, : len(features)] = table[list(features)].to_numpy(dtype=np.float64)
    if constants:
        for j in range(1, len(labels)):
            x[:, j, len(features) + j - 1] = 1.0
    avail[n_idx, e_idx] = True
    chosen = np.zeros(len(answers), dtype=np.int64)
    hit = table["chosen"].to_numpy() == 1
    chosen[n_idx[hit]] = e_idx[hit]
    first = table.drop_duplicates("answer").set_index("answer").loc[answers]
    return x, avail, chosen, first, labels


def clogit_contrast(table: pd.DataFrame, confidence: float = 0.95) -> dict[str, Any]:
    """The primary test of the own-distance model: the pooled conditional logit of the label
    chosen on d_own, d_ref and one constant per label (long table with a ``stimulus`` column),
    two-way cluster-robust (participant, stimulus); the slopes, their odds ratios per unit
    distance and the contrast β_own − β_ref with its CI and t test. ``status`` is ``ok``, or
    ``failed`` with ``reason`` and no estimates (None, never NaN)."""
    from scipy import stats

    chosen_labels = set(table.loc[table["chosen"] == 1, "label"])
    never = sorted(set(table["label"]) - chosen_labels)
    t = table[table["label"].isin(chosen_labels)]
    t = t[t.groupby("answer")["label"].transform("size") >= 2]
    out: dict[str, Any] = {
        "model": "conditional logit (label chosen among those offered), pooled",
        "unit": "participant and stimulus (two-way cluster-robust SE)",
        "confidence": confidence,
        "n_participants": int(t["participant_id"].nunique()),
        "n_stimuli": int(t["stimulus"].nunique()),
        "n_answers": int(t["answer"].nunique()),
        "labels_left_out": never,
        "warnings": [],
    }
    if never:
        out["warnings"].append(
            f"label(s) {', '.join(never)} never chosen: left out of the choice sets (their "
            "constants are −∞ at the maximum)"
        )
    if out["n_participants"] < 2 or out["n_stimuli"] < 2:
        return _no_estimate(out, "fewer than 2 participants or faces with usable answers")
    x, avail, chosen, first, _labels = table_arrays(t, ("d_own", "d_ref"), constants=True)
    fit = conditional_logit(x, avail, chosen)
    out.update(converged=fit.converged, iterations=fit.iterations)
    if not fit.converged:
        return _no_estimate(out, fit.reason)
    directions = np.zeros((3, len(fit.beta)))
    directions[0, 0], directions[1, 1], directions[2, :2] = 1.0, 1.0, (1.0, -1.0)
    weights = directions[2]
    cov = two_way_covariance(
        fit,
        first["participant_id"].astype(str).to_numpy(),
        first["stimulus"].astype(str).to_numpy(),
        directions,
    )
    if cov.note:
        out["warnings"].append(cov.note)
    q = float(stats.t.ppf(0.5 + confidence / 2, cov.df))
    for k, name in enumerate(("own", "ref")):
        se = float(np.sqrt(cov.cov[k, k]))
        out[f"slope_{name}"] = float(fit.beta[k])
        out[f"se_{name}"] = se
        out[f"ci_low_{name}"] = float(fit.beta[k] - q * se)
        out[f"ci_high_{name}"] = float(fit.beta[k] + q * se)
        out[f"odds_ratio_{name}"] = float(np.exp(fit.beta[k]))
    diff = float(weights @ fit.beta)
    se_diff = float(np.sqrt(weights @ cov.cov @ weights))
    if not (np.isfinite(se_diff) and se_diff > 0):
        return _no_estimate(out, f"the contrast's standard error is {se_diff:g}")
    stat = diff / se_diff
    out.update(
        status="ok",
        reason="",
        contrast=diff,
        se_contrast=se_diff,
        ci_low=diff - q * se_diff,
        ci_high=diff + q * se_diff,
        t=stat,
        df=cov.df,
        p=float(2 * stats.t.sf(abs(stat), cov.df)),
        n_participant_clusters=cov.n_participants,
        n_stimulus_clusters=cov.n_stimuli,
    )
    return out


#: The estimate keys of a contrast result (None when there is no estimate).
ESTIMATES = (
    *(f"{k}_{n}" for n in ("own", "ref") for k in ("slope", "se", "ci_low", "ci_high")),
    "odds_ratio_own",
    "odds_ratio_ref",
    "contrast",
    "se_contrast",
    "ci_low",
    "ci_high",
    "p",
)


def _no_estimate(out: dict[str, Any], reason: str) -> dict[str, Any]:
    """A result without estimates: status failed, the reason, every estimate None."""
    return out | dict.fromkeys(ESTIMATES) | {"status": "failed", "reason": reason}
