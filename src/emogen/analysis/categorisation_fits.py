"""The fits of the own-distance model (:mod:`emogen.analysis.categorisation_models`) on its long
table (answer × offered label, chosen 0/1, d_own, d_ref): McFadden's conditional logit by
Newton's method, label constants, the primary GEE contrast and the two-stage model.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

#: Ridge penalty (per unit of slope², on the log-likelihood) of the per-participant fits.
RIDGE = 0.05


def conditional_logit(
    x: np.ndarray, avail: np.ndarray, chosen: np.ndarray, ridge: float = 0.0, iters: int = 50
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """McFadden's conditional logit by Newton's method: x (answers, labels, k) features, avail
    (answers, labels) the labels offered, chosen (answers,). Returns (beta, information, scores):
    the estimate, the (penalised) observed information, and each answer's score at the estimate
    (for sandwich variances)."""
    n, _, k = x.shape
    beta = np.zeros(k)
    rows = np.arange(n)
    for _ in range(iters):
        eta = np.where(avail, x @ beta, -np.inf)
        p = np.exp(eta - eta.max(axis=1, keepdims=True))
        p /= p.sum(axis=1, keepdims=True)
        mean = np.einsum("nl,nlk->nk", p, np.where(avail[..., None], x, 0.0))
        scores = x[rows, chosen] - mean
        centred = np.where(avail[..., None], x - mean[:, None, :], 0.0)
        info = np.einsum("nl,nlk,nlj->kj", p, centred, centred) + ridge * np.eye(k)
        grad = scores.sum(axis=0) - ridge * beta
        step = np.linalg.solve(info, grad)
        beta = beta + step
        if np.max(np.abs(step)) < 1e-9:
            break
    return beta, info, scores


def label_dummies(avail: np.ndarray) -> np.ndarray:
    """(answers, labels, labels − 1) alternative-specific constants (first label the base)."""
    n, e = avail.shape
    d = np.zeros((n, e, e - 1))
    for k in range(1, e):
        d[:, k, k - 1] = 1.0
    return d


def gee_contrast(table: pd.DataFrame, confidence: float = 0.95) -> dict[str, Any]:
    """The primary test: binomial GEE (logit link, exchangeable within participant, robust SE)
    of chosen on d_own, d_ref and label constants; the slopes, their odds ratios per unit
    distance, and the contrast β_own − β_ref with its CI and Wald p (normal reference)."""
    import statsmodels.api as sm
    from scipy import stats

    labels = sorted(table["label"].unique())
    cols: list[np.ndarray] = [table["d_own"].to_numpy(float), table["d_ref"].to_numpy(float)]
    cols.append(np.ones(len(table)))
    cols += [(table["label"] == lab).to_numpy(dtype=float) for lab in labels[1:]]
    x = np.column_stack(cols)
    model = sm.GEE(
        table["chosen"].to_numpy(dtype=float),
        x,
        groups=table["participant_id"].to_numpy(),
        family=sm.families.Binomial(),
        cov_struct=sm.cov_struct.Exchangeable(),
    )
    fit = model.fit(maxiter=100)
    beta, cov = np.asarray(fit.params), np.asarray(fit.cov_params())
    z = stats.norm.ppf(0.5 + confidence / 2)
    diff = float(beta[0] - beta[1])
    se_diff = float(np.sqrt(cov[0, 0] + cov[1, 1] - 2 * cov[0, 1]))
    out: dict[str, Any] = {"unit": "participant (clusters of the GEE)", "confidence": confidence}
    for k, name in enumerate(("own", "ref")):
        se = float(np.sqrt(cov[k, k]))
        out[f"slope_{name}"] = float(beta[k])
        out[f"se_{name}"] = se
        out[f"ci_low_{name}"], out[f"ci_high_{name}"] = beta[k] - z * se, beta[k] + z * se
        out[f"odds_ratio_{name}"] = float(np.exp(beta[k]))
    out.update(
        contrast=diff,
        se_contrast=se_diff,
        ci_low=diff - z * se_diff,
        ci_high=diff + z * se_diff,
        z=diff / se_diff,
        p=float(2 * stats.norm.sf(abs(diff / se_diff))),
        correlation=float(np.asarray(fit.cov_struct.dep_params)),
        n_participants=int(table["participant_id"].nunique()),
        n_answers=int(table.groupby(["participant_id", "answer"]).ngroups),
    )
    return out


def per_participant_slopes(table: pd.DataFrame, ridge: float = RIDGE) -> pd.DataFrame:
    """The two-stage model's first stage: per participant, a ridge-penalised conditional logit
    of the chosen label on d_own and d_ref (no label constants)."""
    rows = []
    for pid, part in table.groupby("participant_id", sort=True):
        x, avail, chosen = _arrays(part, ("d_own", "d_ref"))
        beta, _info, _s = conditional_logit(x, avail, chosen, ridge=ridge)
        rows.append(
            {
                "participant_id": pid,
                "n_answers": len(chosen),
                "slope_own": beta[0],
                "slope_ref": beta[1],
                "contrast": beta[0] - beta[1],
            }
        )
    return pd.DataFrame(rows)


def _arrays(
    part: pd.DataFrame, features: tuple[str, ...]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A long table's answers as (answers, labels, k) features, availability and choices."""
    labels = sorted(part["label"].unique())
    answers = np.unique(part["answer"].to_numpy())
    n_idx = np.searchsorted(answers, part["answer"].to_numpy())
    e_idx = np.searchsorted(labels, part["label"].to_numpy())
    x = np.zeros((len(answers), len(labels), len(features)))
    avail = np.zeros((len(answers), len(labels)), dtype=bool)
    x[n_idx, e_idx] = part[list(features)].to_numpy(dtype=np.float64)
    avail[n_idx, e_idx] = True
    chosen = np.zeros(len(answers), dtype=np.int64)
    hit = part["chosen"].to_numpy() == 1
    chosen[n_idx[hit]] = e_idx[hit]
    return x, avail, chosen


def two_stage(slopes: pd.DataFrame, confidence: float = 0.95) -> dict[str, Any]:
    """The second stage: one-sample t (with CI) and Wilcoxon signed-rank test of the per-
    participant contrasts (own − reference slope) over participants."""
    from scipy import stats

    c = slopes["contrast"].to_numpy(dtype=float)
    out: dict[str, Any] = {
        "unit": "participant",
        "n_participants": len(c),
        "mean_contrast": float(c.mean()) if len(c) else float("nan"),
        "median_contrast": float(np.median(c)) if len(c) else float("nan"),
    }
    if len(c) < 3 or np.allclose(c, c[0]):
        return {
            **out,
            "t": float("nan"),
            "p_t": float("nan"),
            "p_wilcoxon": float("nan"),
            "ci_low": float("nan"),
            "ci_high": float("nan"),
        }
    t = stats.ttest_1samp(c, 0.0)
    ci = t.confidence_interval(confidence)
    return {
        **out,
        "t": float(t.statistic),
        "p_t": float(t.pvalue),
        "ci_low": float(ci.low),
        "ci_high": float(ci.high),
        "p_wilcoxon": float(stats.wilcoxon(c).pvalue),
    }
