"""The secondary fits of the own-distance model (:mod:`emogen.analysis.categorisation_models`)
on its long table (answer × offered label, chosen 0/1, d_own, d_ref): the GEE contrast and the
two-stage model. The primary fit, the pooled conditional logit with two-way clustering, is
:mod:`emogen.analysis.categorisation_clogit`. Every fit says whether it converged; a failed fit
has ``status`` ``failed``, its ``reason`` and no estimates (None), a fallback is named in
``warnings``.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pandas as pd

from emogen.analysis.categorisation_clogit import (
    ESTIMATES,
    conditional_logit,
    table_arrays,
)


def label_constants(avail: np.ndarray) -> np.ndarray:
    """(answers, labels, m) alternative-specific constants for the labels offered somewhere,
    but the first of them (the base)."""
    present = np.flatnonzero(avail.any(axis=0))
    d = np.zeros((*avail.shape, max(len(present) - 1, 0)))
    for j, lab in enumerate(present[1:]):
        d[:, lab, j] = 1.0
    return d


def gee_contrast(table: pd.DataFrame, confidence: float = 0.95) -> dict[str, Any]:
    """Secondary: binomial GEE (logit link, robust SE over participants) of chosen on d_own,
    d_ref and label constants; the slopes, their odds ratios per unit distance, and the
    contrast β_own − β_ref with its CI and Wald p (normal reference). The working correlation
    is exchangeable within participant; when that fit fails (no convergence, a correlation at
    its bound, a non-finite or zero standard error) the independence working correlation is
    the fallback, named in ``warnings``; when both fail, ``status`` is ``failed``."""
    import statsmodels.api as sm

    labels = sorted(table["label"].unique())
    cols: list[np.ndarray] = [table["d_own"].to_numpy(float), table["d_ref"].to_numpy(float)]
    cols.append(np.ones(len(table)))
    cols += [(table["label"] == lab).to_numpy(dtype=float) for lab in labels[1:]]
    x = np.column_stack(cols)
    out: dict[str, Any] = {
        "model": "GEE (binomial, logit link) on answer × offered label",
        "unit": "participant (clusters of the GEE)",
        "confidence": confidence,
        "n_participants": int(table["participant_id"].nunique()),
        "n_answers": int(table.groupby(["participant_id", "answer"]).ngroups),
        "warnings": [],
    }
    for structure in (sm.cov_struct.Exchangeable(), sm.cov_struct.Independence()):
        name = type(structure).__name__.lower()
        fitted = _gee_fit(table, x, structure, confidence)
        if isinstance(fitted, str):
            out["warnings"].append(f"{name} working correlation: {fitted}")
            continue
        if name != "exchangeable":
            out["warnings"].append("fallback: independence working correlation")
        return out | fitted | {"working_correlation": name, "status": "ok", "reason": ""}
    reason = "; ".join(out["warnings"])
    return out | dict.fromkeys(ESTIMATES) | {"status": "failed", "reason": reason}


def _gee_fit(
    table: pd.DataFrame, x: np.ndarray, structure: Any, confidence: float
) -> dict[str, Any] | str:
    """One GEE fit's estimates, or why it failed."""
    import statsmodels.api as sm
    from scipy import stats

    model = sm.GEE(
        table["chosen"].to_numpy(dtype=float),
        x,
        groups=table["participant_id"].to_numpy(),
        family=sm.families.Binomial(),
        cov_struct=structure,
    )
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = model.fit(maxiter=100)
    except (np.linalg.LinAlgError, ValueError, ZeroDivisionError) as exc:
        return f"the fit stopped ({exc})"
    beta = np.asarray(fit.params, dtype=float)
    cov = np.asarray(fit.cov_params(), dtype=float)
    dep_params = getattr(fit.cov_struct, "dep_params", None)  # None for independence
    dep = np.atleast_1d(np.asarray(0.0 if dep_params is None else dep_params, dtype=float))
    if not getattr(fit, "converged", True):
        return "no convergence in 100 iterations"
    if not (np.all(np.isfinite(beta)) and np.all(np.isfinite(cov)) and np.all(np.isfinite(dep))):
        return "the estimates diverged (non-finite values)"
    diff = float(beta[0] - beta[1])
    se_diff_sq = float(cov[0, 0] + cov[1, 1] - 2 * cov[0, 1])
    if not se_diff_sq > 0:
        return f"the contrast's standard error is {np.sqrt(max(se_diff_sq, 0.0)):g}"
    se_diff = float(np.sqrt(se_diff_sq))
    z = stats.norm.ppf(0.5 + confidence / 2)
    out: dict[str, Any] = {}
    for k, name in enumerate(("own", "ref")):
        se = float(np.sqrt(cov[k, k]))
        out[f"slope_{name}"] = float(beta[k])
        out[f"se_{name}"] = se
        out[f"ci_low_{name}"], out[f"ci_high_{name}"] = beta[k] - z * se, beta[k] + z * se
        out[f"odds_ratio_{name}"] = float(np.exp(beta[k]))
    return out | {
        "contrast": diff,
        "se_contrast": se_diff,
        "ci_low": diff - z * se_diff,
        "ci_high": diff + z * se_diff,
        "z": diff / se_diff,
        "p": float(2 * stats.norm.sf(abs(diff / se_diff))),
        "correlation": float(dep[0]),
        "converged": True,
    }


def per_participant_slopes(table: pd.DataFrame) -> pd.DataFrame:
    """The two-stage model's first stage: per participant, the maximum-likelihood conditional
    logit of the chosen label on d_own and d_ref (no label constants, no penalty). A
    participant whose fit has no estimate (separation: their labels perfectly predicted; a
    singular information) has ``converged`` False, the ``reason``, and NA slopes."""
    rows = []
    for pid, part in table.groupby("participant_id", sort=True):
        x, avail, chosen, _first, _labels = table_arrays(part, ("d_own", "d_ref"), False)
        fit = conditional_logit(x, avail, chosen)
        rows.append(
            {
                "participant_id": pid,
                "n_answers": len(chosen),
                "converged": fit.converged,
                "slope_own": fit.beta[0],
                "slope_ref": fit.beta[1],
                "contrast": fit.beta[0] - fit.beta[1],
                "reason": fit.reason,
            }
        )
    return pd.DataFrame(rows)


def two_stage(slopes: pd.DataFrame, confidence: float = 0.95) -> dict[str, Any]:
    """The second stage: one-sample t (with CI) and Wilcoxon signed-rank test of the per-
    participant contrasts (own − reference slope) over the participants whose first-stage fit
    converged (the others are named in ``warnings``). Leaving them out keeps the test valid
    under the null: swapping own and reference faces leaves a participant's chance of
    separation unchanged."""
    from scipy import stats

    ok = slopes[slopes["converged"].astype(bool)]
    c = ok["contrast"].to_numpy(dtype=float)
    out: dict[str, Any] = {
        "model": "two-stage: per-participant conditional logit (unpenalised), then over "
        "participants",
        "unit": "participant",
        "n_participants": len(c),
        "warnings": [],
    }
    dropped = slopes.loc[~slopes["converged"].astype(bool), "participant_id"].astype(str)
    if len(dropped):
        out["warnings"].append(
            f"{len(dropped)} participant(s) without a first-stage estimate left out "
            f"({', '.join(dropped[:5])}{', …' if len(dropped) > 5 else ''}): their labels are "
            "perfectly predicted by the distances, or their fit is singular"
        )
    if len(c) < 3 or np.allclose(c, c[0]):
        keys = ("mean_contrast", "median_contrast", "t", "p_t", "p_wilcoxon", "ci_low", "ci_high")
        reason = (
            f"{len(c)} participant(s) with a first-stage estimate; the test needs 3 that differ"
        )
        return out | dict.fromkeys(keys) | {"status": "failed", "reason": reason}
    t = stats.ttest_1samp(c, 0.0)
    ci = t.confidence_interval(confidence)
    return out | {
        "status": "ok",
        "reason": "",
        "mean_contrast": float(c.mean()),
        "median_contrast": float(np.median(c)),
        "t": float(t.statistic),
        "p_t": float(t.pvalue),
        "ci_low": float(ci.low),
        "ci_high": float(ci.high),
        "p_wilcoxon": float(stats.wilcoxon(c).pvalue),
    }
