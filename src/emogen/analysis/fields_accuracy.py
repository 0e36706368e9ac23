"""Does a person's own face space predict how well they recognise others' faces? The
relation at the centre of "Expression perceptive fields" (Commun. Psychol. 2024): people whose
expressions of different emotions overlap more recognise emotions less accurately.

Per participant (the unit):

* **distinctness**: the mean over pairs of emotions of the gene-space Euclidean distance
  between the participant's mean final faces of the two emotions (every identity and
  repetition pooled) — how far apart their own expressions of different emotions lie (small:
  overlapping fields);
* **accuracy**: the share of their answers that name the intended emotion, over faces they did
  not make (others' and file faces; fallback stand-ins and faces without an intended emotion
  left out).

Test: Pearson's r over participants, its 95% CI by Fisher's z (assumes bivariate normality
roughly; Spearman's ρ given beside it), and a two-sided permutation p (accuracies shuffled
among participants, 4999 permutations: no distributional assumption, exact under
exchangeability of participants). Effect size: r, and the slope (accuracy per unit of
distinctness) by least squares.
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from scipy import stats

from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.people import People

if TYPE_CHECKING:
    from emogen.analysis.results import Section

#: The fewest participants with both measures the relation is tested on.
MIN_PARTICIPANTS = 8
#: Permutations of the report's test.
PERMUTATIONS = 4999


def participant_measures(people: People) -> pd.DataFrame:
    """One row per participant with both measures: ``participant_id``, ``distinctness``,
    ``n_answers``, ``accuracy``."""
    faces = people.faces.assign(participant_id=people.faces["participant_id"].astype(str))
    means = faces.groupby(["participant_id", "emotion"])[list(people.genes)].mean()
    rows = []
    for pid, block in means.groupby(level="participant_id"):
        m = block.to_numpy(dtype=np.float64)
        if len(m) < 2:
            continue
        pairs = itertools.combinations(range(len(m)), 2)
        rows.append(
            {
                "participant_id": pid,
                "distinctness": np.mean([np.linalg.norm(m[a] - m[b]) for a, b in pairs]),
            }
        )
    dist = pd.DataFrame(rows, columns=["participant_id", "distinctness"])
    r = people.responses
    if r is None or r.empty or "label" not in r.columns:
        return dist.assign(n_answers=0, accuracy=np.nan).iloc[:0]
    r = r[r["label"].notna() & r["intended"].notna() & r["source"].isin(["other", "file"])]
    if "fallback" in r.columns:
        r = r[~r["fallback"].fillna(False).astype(bool)]
    hit = (r["label"].astype(str) == r["intended"].astype(str)).astype(float)
    acc = (
        r.assign(hit=hit, participant_id=r["participant_id"].astype(str))
        .groupby("participant_id")["hit"]
        .agg(n_answers="size", accuracy="mean")
        .reset_index()
    )
    return dist.merge(acc, on="participant_id", how="inner")


def distinctness_accuracy(
    people: People, *, rng: np.random.Generator, permutations: int = PERMUTATIONS
) -> dict[str, Any]:
    """The relation of distinctness to accuracy over participants (module docstring);
    ``status`` ``failed`` with the reason (no estimates) when it cannot be tested."""
    table = participant_measures(people)
    out: dict[str, Any] = {
        "test": "Pearson r over participants (Fisher-z CI; permutation p)",
        "unit": "participant",
        "n_participants": len(table),
        "table": table,
    }
    x, y = table["distinctness"].to_numpy(float), table["accuracy"].to_numpy(float)
    keys = ("r", "ci_low", "ci_high", "p", "p_perm", "spearman", "slope")
    if len(table) < MIN_PARTICIPANTS:
        why = (
            f"{len(table)} participants have both final faces of two or more emotions and "
            f"answers to faces they did not make; the test needs {MIN_PARTICIPANTS}"
        )
        return out | dict.fromkeys(keys) | {"status": "failed", "reason": why}
    if np.ptp(x) == 0 or np.ptp(y) == 0:
        what = "distinctness" if np.ptp(x) == 0 else "accuracy"
        why = f"every participant has the same {what}: no correlation to estimate"
        return out | dict.fromkeys(keys) | {"status": "failed", "reason": why}
    r = float(np.corrcoef(x, y)[0, 1])
    z, half = np.arctanh(np.clip(r, -0.9999999, 0.9999999)), 1.959964 / np.sqrt(len(x) - 3)
    shuffled = np.array([np.corrcoef(x, rng.permutation(y))[0, 1] for _ in range(permutations)])
    return out | {
        "status": "ok",
        "reason": "",
        "r": r,
        "ci_low": float(np.tanh(z - half)),
        "ci_high": float(np.tanh(z + half)),
        "p": float(stats.pearsonr(x, y).pvalue),
        "p_perm": float((1 + np.sum(np.abs(shuffled) >= abs(r) - 1e-12)) / (1 + permutations)),
        "spearman": float(stats.spearmanr(x, y).statistic),
        "slope": float(np.polyfit(x, y, 1)[0]),
        "permutations": permutations,
    }


def fields_accuracy_section(
    people: People, report: Section, out: dict[str, Any], opts: AnalysisOptions
) -> None:
    """The report's paragraph and table on distinctness and accuracy
    (``out["fields_accuracy"]``)."""
    res = distinctness_accuracy(people, rng=np.random.default_rng(opts.seed))
    table = res.pop("table")
    out["fields_accuracy"] = res
    report.heading("Own expressions and recognition accuracy (perceptive fields, 2024)", level=3)
    head = (
        "Per participant (the unit): distinctness, the mean gene-space distance between their "
        "own mean faces of each pair of emotions (small: their expressions of different "
        "emotions overlap), against their accuracy on faces they did not make (others' and "
        "file faces; fallback faces left out). Pearson's r over participants with a Fisher-z "
        f"95% CI (assumes rough bivariate normality) and a permutation p ({PERMUTATIONS} "
        f"shuffles of accuracy among participants, seed {opts.seed}): "
    )
    name = "categorisation.fields_accuracy"
    if res["status"] != "ok":
        report.not_run(name, res["reason"], res, n=res["n_participants"])
        report.paragraph(head + f"**not estimated** — {res['reason']}.")
        return
    report.add_test(
        name,
        res,
        test=res["test"],
        p=res["p_perm"],  # the calibrated p (docs/analysis.md: 34 of 1000 null studies)
        n=res["n_participants"],
        statistic=res["r"],
        estimate=res["r"],
        interval=(res["ci_low"], res["ci_high"]),
        level=0.95,
        effect=("r", res["r"], res["ci_low"], res["ci_high"]),
    )
    report.table(table, "categorisation_distinctness", "Distinctness and accuracy per participant")
    report.paragraph(
        head + f"r = {res['r']:+.2f}, 95% CI [{res['ci_low']:+.2f}, {res['ci_high']:+.2f}], "
        f"permutation p = {res['p_perm']:.3g} (t-test p = {res['p']:.3g}); Spearman ρ = "
        f"{res['spearman']:+.2f}; slope {res['slope']:+.3f} accuracy per unit distance "
        f"(n = {res['n_participants']})."
    )
