"""Categorisation of faces by the participants who made them (the ``responses`` table of a study
export): accuracy on one's own faces against accuracy on other participants' faces.

Binetti et al. (2022, PNAS 119:e2201380119) found participants' categorisation of test faces
explained by how close each face lay to the faces they had made themselves; the simplest form of
that prediction is that a participant labels their own faces more accurately than others' faces.

The participant is the unit: each participant's accuracy on own faces and on others' faces
(answered trials whose face has a known intended emotion; fallback faces — random stand-ins
for others' faces — left out), then a paired comparison over participants (one-sample t on the
per-participant differences, with its 95% CI; scipy.stats.ttest_1samp).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.errors import DataError

if TYPE_CHECKING:
    from emogen.analysis.report import Report


def accuracy_by_source(responses: pd.DataFrame) -> pd.DataFrame:
    """One row per participant: ``n_own``, ``accuracy_own``, ``n_other``, ``accuracy_other``
    (NA where the participant has no such faces)."""
    needed = {"participant_id", "source", "fallback", "intended", "label"}
    missing = sorted(needed - set(responses.columns))
    if missing:
        raise DataError(f"the responses table lacks column(s) {missing}: is it a study export's?")
    r = responses[sorted(needed)]
    r = r[r["label"].notna() & r["intended"].notna()]
    r = r[~r["fallback"].fillna(False).astype(bool)]
    r = r.assign(hit=(r["label"] == r["intended"]).astype(float))
    out = {}
    for source in ("own", "other"):
        part = r[r["source"] == source].groupby("participant_id")["hit"]
        out[f"n_{source}"] = part.size()
        out[f"accuracy_{source}"] = part.mean()
    table = pd.DataFrame(out)
    table[["n_own", "n_other"]] = table[["n_own", "n_other"]].fillna(0).astype("Int64")
    return table.reset_index()


def own_advantage(responses: pd.DataFrame, confidence: float = 0.95) -> dict[str, Any]:
    """Own-face minus other-face accuracy over participants with both: mean, CI, t, p."""
    from scipy import stats

    per = accuracy_by_source(responses).dropna(subset=["accuracy_own", "accuracy_other"])
    diff = (per["accuracy_own"] - per["accuracy_other"]).to_numpy(dtype=float)
    n = len(diff)
    result: dict[str, Any] = {
        "unit": "participant",
        "test": "one-sample t on per-participant accuracy differences (own − other)",
        "n_participants": n,
        "accuracy_own": float(per["accuracy_own"].mean()) if n else float("nan"),
        "accuracy_other": float(per["accuracy_other"].mean()) if n else float("nan"),
        "difference": float(diff.mean()) if n else float("nan"),
    }
    if n < 2 or np.allclose(diff, diff[0]):
        result.update(ci_low=float("nan"), ci_high=float("nan"), t=float("nan"), p=float("nan"))
        result["note"] = f"{n} participant(s) with own and others' faces; no test"
        return result
    test = stats.ttest_1samp(diff, 0.0)
    ci = test.confidence_interval(confidence)
    result.update(ci_low=float(ci.low), ci_high=float(ci.high), t=float(test.statistic),
                  p=float(test.pvalue), confidence=confidence)  # fmt: skip
    return result


def categorisation_section(
    responses: pd.DataFrame | None, report: Report, summary: dict[str, Any]
) -> None:
    """The report's section on a study's categorise answers: accuracy by face source, and own-
    against other-face accuracy with the participant as the unit (nothing without answers)."""
    if responses is None or responses.empty or "label" not in responses.columns:
        return
    answered = responses[responses["label"].notna()]
    report.heading("Categorisation of faces")
    if answered.empty:
        report.paragraph("The study has categorise trials, but none has been answered yet.")
        summary["categorisation"] = {"n_answers": 0}
        return
    fallback = answered["fallback"].fillna(False).astype(bool)
    known = answered[answered["intended"].notna() & ~fallback]
    by_source = (
        known.assign(hit=(known["label"] == known["intended"]).astype(float))
        .groupby("source")
        .agg(
            participants=("participant_id", "nunique"),
            answers=("hit", "size"),
            accuracy=("hit", "mean"),
        )
        .reset_index()
    )
    report.paragraph(
        f"{len(answered)} answers of {answered['participant_id'].nunique()} participants; "
        f"{len(answered) - len(known)} of them are to faces with no right answer (random "
        "faces, file rows without a label) or to stand-ins for others' faces (fallback): "
        "those are not in the accuracies. The pooled accuracies describe the answers; the test "
        "below is over participants."
    )
    report.table(by_source, "categorisation_by_source", "Accuracy by face source (pooled)")
    per = accuracy_by_source(responses)
    report.table(per, "categorisation_participants", "Accuracy per participant")
    adv = own_advantage(responses)
    summary["categorisation"] = {"n_answers": len(answered), "own_advantage": adv}
    if np.isnan(adv["ci_low"]):
        report.paragraph(f"Own- against other-face accuracy: {adv['note']}.")
        return
    report.paragraph(
        f"Own- against other-face accuracy ({adv['test']}; the participant is the unit, "
        f"n = {adv['n_participants']}; fallback faces left out): own "
        f"{adv['accuracy_own']:.3f}, others' {adv['accuracy_other']:.3f}, difference "
        f"{adv['difference']:+.3f}, 95% CI [{adv['ci_low']:+.3f}, {adv['ci_high']:+.3f}], "
        f"t = {adv['t']:.2f}, p = {adv['p']:.3g}."
    )
