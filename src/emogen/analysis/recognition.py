"""Recognition statistics of categorise answers: confusion matrices, Wagner's unbiased hit rates
with their chance proportions, and accuracy by face source — the participant the unit of every
test.

* **Confusion matrices** (intended × label): counts and row proportions, over all answers and per
  face source (``own``/``other``/``file``; ``random`` faces have no intended emotion: their row is
  the distribution of the labels given to them, intended ``(random)``). Pooled over answers:
  descriptive.
* **Unbiased hit rate** (Wagner 1993, J. Nonverbal Behav. 17:3–28): per participant and
  emotion e, from the participant's own confusion matrix over faces with an intended emotion,
  Hu = n_ee² / (n_e· × n_·e) — the hits over the faces of e times the hits over the uses of
  label e — and its chance proportion pc = (n_e· / N) × (n_·e / N). Per emotion, the
  participants' arcsine-square-root transformed Hu minus pc is tested by a one-sample t over
  participants (with its CI), Holm-corrected over emotions.
* **Accuracy by source**: per participant and source, the share of answers equal to the
  intended emotion (fallback faces — stand-ins for others' faces — left out); each pair of
  sources compared over the participants with both by a paired t (CI), Holm-corrected.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pandas as pd

from emogen.errors import DataError

#: Face sources with an intended emotion, in report order.
KNOWN_SOURCES = ("own", "other", "file")
#: The ``intended`` value of random faces' rows in a confusion table.
RANDOM_ROW = "(random)"


def answered(responses: pd.DataFrame) -> pd.DataFrame:
    """The answered categorise trials, typed: ``participant_id`` a string, ``fallback`` a
    bool, ``intended`` NA for random and fallback faces (they have no right answer)."""
    needed = {"participant_id", "source", "intended", "label"}
    missing = sorted(needed - set(responses.columns))
    if missing:
        raise DataError(f"the responses table lacks column(s) {missing}: is it a study export's?")
    r = responses[responses["label"].notna()]
    fallback = (
        r["fallback"].fillna(False).astype(bool)
        if "fallback" in r.columns
        else pd.Series(False, index=r.index)
    )
    intended = r["intended"].where(~fallback & (r["source"] != "random"))
    return r.assign(
        participant_id=r["participant_id"].astype(str),
        fallback=fallback,
        intended=intended,
        label=r["label"].astype(str),
        source=r["source"].astype(str),
    )


def confusion_table(responses: pd.DataFrame) -> pd.DataFrame:
    """Long confusion table: ``source`` (``all`` and each source), ``intended``, ``label``,
    ``count``, ``proportion`` (of the row: the faces of that source and intended emotion)."""
    r = answered(responses)
    known = r[r["intended"].notna()]
    rand = r[r["source"] == "random"].assign(intended=RANDOM_ROW)
    parts = [known.assign(source="all"), known, rand]
    frame = pd.concat(parts, ignore_index=True)
    if frame.empty:
        return pd.DataFrame(columns=["source", "intended", "label", "count", "proportion"])
    frame = frame.assign(intended=frame["intended"].astype(str))
    counts = frame.groupby(["source", "intended", "label"]).size().rename("count")
    out = counts.reset_index()
    totals = out.groupby(["source", "intended"])["count"].transform("sum")
    out["proportion"] = out["count"] / totals
    order = {s: k for k, s in enumerate(("all", *KNOWN_SOURCES, "random"))}
    out = out.sort_values(
        ["source", "intended", "label"], key=lambda c: c.map(order) if c.name == "source" else c
    )
    return out.reset_index(drop=True).astype({"count": "int64"})


def unbiased_hit_rates(responses: pd.DataFrame) -> pd.DataFrame:
    """Per participant × emotion (the emotions intended for the participant's faces): ``n_faces``
    (n_e·), ``n_label`` (n_·e), ``hits`` (n_ee), ``n_answers`` (N), ``hu``, ``pc``."""
    r = answered(responses)
    r = r[r["intended"].notna()].assign(intended=lambda d: d["intended"].astype(str))
    rows = []
    for pid, part in r.groupby("participant_id", sort=True):
        n = len(part)
        for emotion in sorted(part["intended"].unique()):
            faces = int((part["intended"] == emotion).sum())
            used = int((part["label"] == emotion).sum())
            hits = int(((part["intended"] == emotion) & (part["label"] == emotion)).sum())
            hu = hits**2 / (faces * used) if used else 0.0
            rows.append(
                {
                    "participant_id": pid,
                    "emotion": emotion,
                    "n_faces": faces,
                    "n_label": used,
                    "hits": hits,
                    "n_answers": n,
                    "hu": hu,
                    "pc": faces * used / n**2,
                }
            )
    cols = ["participant_id", "emotion", "n_faces", "n_label", "hits", "n_answers", "hu", "pc"]
    return pd.DataFrame(rows, columns=cols)


def holm(p: np.ndarray) -> np.ndarray:
    """Holm's step-down adjusted p-values (NaN stays NaN)."""
    from statsmodels.stats.multitest import multipletests

    p = np.asarray(p, dtype=float)
    out = np.full(len(p), np.nan)
    ok = np.isfinite(p)
    if ok.any():
        out[ok] = multipletests(p[ok], method="holm")[1]
    return out


def _paired(diff: np.ndarray, confidence: float) -> dict[str, float]:
    """One-sample t of ``diff`` against 0: mean, CI, t, p (NaN below 2 distinct values)."""
    from scipy import stats

    nan = float("nan")
    if len(diff) < 2 or np.allclose(diff, diff[0]):
        mean = float(diff.mean()) if len(diff) else nan
        return {"mean_difference": mean, "ci_low": nan, "ci_high": nan, "t": nan, "p": nan}
    test = stats.ttest_1samp(diff, 0.0)
    ci = test.confidence_interval(confidence)
    return {
        "mean_difference": float(diff.mean()),
        "ci_low": float(ci.low),
        "ci_high": float(ci.high),
        "t": float(test.statistic),
        "p": float(test.pvalue),
    }


def hu_tests(hu: pd.DataFrame, alpha: float = 0.05, confidence: float = 0.95) -> pd.DataFrame:
    """Per emotion: arcsin√Hu − arcsin√pc over participants (one-sample t, CI; Holm)."""
    rows = []
    for emotion, part in hu.groupby("emotion", sort=True):
        diff = np.arcsin(np.sqrt(part["hu"].to_numpy(float))) - np.arcsin(
            np.sqrt(part["pc"].to_numpy(float))
        )
        rows.append(
            {
                "emotion": emotion,
                "n_participants": len(part),
                "mean_hu": float(part["hu"].mean()),
                "mean_pc": float(part["pc"].mean()),
                **_paired(diff, confidence),
            }
        )
    out = pd.DataFrame(rows)
    if out.empty:
        return out
    out["p_holm"] = holm(out["p"].to_numpy())
    out["above_chance"] = (out["p_holm"] <= alpha) & (out["mean_difference"] > 0)
    return out


def accuracy_per_participant(responses: pd.DataFrame) -> pd.DataFrame:
    """Long: ``participant_id``, ``source`` (own/other/file), ``n`` answers, ``accuracy``."""
    r = answered(responses)
    r = r[r["intended"].notna()]
    hit = (r["label"] == r["intended"].astype(str)).astype(float)
    out = r.assign(hit=hit).groupby(["participant_id", "source"])["hit"].agg(["size", "mean"])
    out = out.reset_index().rename(columns={"size": "n", "mean": "accuracy"})
    return out.astype({"n": "int64"})


def source_comparisons(
    per: pd.DataFrame, alpha: float = 0.05, confidence: float = 0.95
) -> pd.DataFrame:
    """Every pair of sources present: paired t over the participants with both (Holm)."""
    wide = per.pivot(index="participant_id", columns="source", values="accuracy")
    present = [s for s in KNOWN_SOURCES if s in wide.columns]
    rows = []
    for a, b in combinations(present, 2):
        both = wide[[a, b]].dropna()
        diff = (both[a] - both[b]).to_numpy(float)
        rows.append(
            {
                "source_a": a,
                "source_b": b,
                "n_participants": len(both),
                "accuracy_a": float(both[a].mean()) if len(both) else float("nan"),
                "accuracy_b": float(both[b].mean()) if len(both) else float("nan"),
                **_paired(diff, confidence),
            }
        )
    out = pd.DataFrame(rows)
    if not out.empty:
        out["p_holm"] = holm(out["p"].to_numpy())
        out["significant"] = out["p_holm"] <= alpha
    return out
