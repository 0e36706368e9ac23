"""Categorisation of faces by the participants who made them (the ``categorise_responses``
table of a study export): accuracy on one's own faces against accuracy on other participants'
faces, and the report section of every categorisation analysis
(:mod:`emogen.analysis.recognition`: confusion matrices, unbiased hit rates, accuracy by
source; :mod:`emogen.analysis.categorisation_models`: labels predicted by the distance to one's
own faces).

Binetti et al. (2022, PNAS 119:e2201380119) found participants' categorisation of test faces
explained by how close each face lay to the faces they had made themselves; the simplest form of
that prediction is that a participant labels their own faces more accurately than others' faces.

The participant is the unit: each participant's accuracy on own faces and on others' faces
(answered trials whose face has a known intended emotion; fallback faces — random stand-ins
for others' faces — left out), then a paired comparison over participants (one-sample t on the
per-participant differences, with its 95% CI; scipy.stats.ttest_1samp).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.analysis import recognition as rec
from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.fields_accuracy import fields_accuracy_section
from emogen.analysis.own_distance_report import own_distance_section
from emogen.analysis.people import People
from emogen.analysis.results import Section
from emogen.errors import DataError

if TYPE_CHECKING:
    from emogen.analysis.report import Content
    from emogen.model.face import FaceModel


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
    dz_low, dz_high = dz_interval(float(test.statistic), n, confidence)
    result.update(
        ci_low=float(ci.low),
        ci_high=float(ci.high),
        t=float(test.statistic),
        p=float(test.pvalue),
        confidence=confidence,
        dz=float(test.statistic) / np.sqrt(n),
        dz_low=dz_low,
        dz_high=dz_high,
    )
    return result


def dz_interval(t: float, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """CI of Cohen's dz (mean difference / SD of the differences) from a one-sample t on n
    participants: the noncentral-t inversion (exact under normal differences; Steiger & Fouladi
    1997) — the noncentralities whose t distributions put ``t`` at their upper and lower
    (1 − confidence)/2 tails, divided by √n. Where scipy's noncentral t cannot be inverted
    (far tails), the normal approximation dz ± z·√(1/n + dz²/(2n))."""
    from scipy import optimize, stats

    tail = (1 - confidence) / 2

    def at(q: float) -> float:
        f = lambda nc: float(stats.nct.cdf(t, n - 1, nc)) - q  # noqa: E731
        span = abs(t) + 10.0
        return float(optimize.brentq(f, t - span, t + span)) / np.sqrt(n)

    try:
        low, high = at(1 - tail), at(tail)
    except ValueError:  # NaN from nct.cdf, or no sign change in the bracket
        low = high = float("nan")
    if np.isfinite(low) and np.isfinite(high):
        return low, high
    dz = t / np.sqrt(n)
    half = float(stats.norm.ppf(1 - tail)) * np.sqrt(1 / n + dz**2 / (2 * n))
    return float(dz - half), float(dz + half)


def categorisation_section(
    people: People | pd.DataFrame | None,
    folder: Path,
    opts: AnalysisOptions | None = None,
    model: FaceModel | None = None,
) -> Section:
    """The report's section on a study's categorise answers (``analysis.json``'s ``categorisation``).

    ``people``: the study (:class:`People`: every analysis), or only its responses table (the
    older call: no own-distance model, which needs the final faces; nothing at all is written
    without answers, as a GA dataset has none). ``model`` is not used (faces are compared in
    gene space)."""
    report = Section(folder)
    opts = opts or AnalysisOptions()
    full = people if isinstance(people, People) else None
    responses = full.responses if full is not None else people
    if not isinstance(responses, pd.DataFrame) or responses.empty or "label" not in responses:
        if full is not None:
            report.heading("Categorisation of faces")
            report.paragraph(
                "No categorisation analysis: no categorise answers (the study has no categorise "
                "block, or nobody has reached it yet)."
            )
            report.data["categorisation"] = {"n_answers": 0, "note": "no categorise answers"}
        return report
    report.heading("Categorisation of faces")
    answered = rec.answered(responses)
    if answered.empty:
        report.paragraph(
            "No categorisation analysis: the study's categorise trials are unanswered."
        )
        report.data["categorisation"] = {"n_answers": 0, "note": "no answers"}
        return report
    out: dict[str, Any] = {
        "n_answers": len(answered),
        "n_participants": int(answered["participant_id"].nunique()),
    }
    report.data["categorisation"] = out
    _overview(responses, answered, report, out)
    _confusion(responses, report)
    _hit_rates(responses, report, out, opts)
    _sources(responses, report, out, opts)
    if full is None:
        report.paragraph(
            "Own-distance model: not fitted here (it needs the study's final faces, which "
            "this call did not receive)."
        )
        return report
    own_distance_section(full, report, out, opts)
    fields_accuracy_section(full, report, out, opts)
    return report


def _long(report: Content, table: pd.DataFrame, name: str, caption: str, shown: int = 8) -> None:
    """A long table: its first rows in the report, every row in ``tables/<name>.csv``."""
    more = len(table) > shown
    note = f" (first {shown} of {len(table)} rows; all in tables/{name}.csv)" if more else ""
    report.table(table.head(shown), name, caption + note, data=table)


def _overview(
    responses: pd.DataFrame, answered: pd.DataFrame, report: Content, out: dict[str, Any]
) -> None:
    known = answered[answered["intended"].notna()]
    by_source = (
        answered.assign(
            hit=(answered["label"] == answered["intended"])
            .astype(float)
            .where(answered["intended"].notna())
        )
        .groupby("source")
        .agg(
            participants=("participant_id", "nunique"),
            answers=("label", "size"),
            accuracy=("hit", "mean"),
        )
        .reset_index()
    )
    report.paragraph(
        f"{len(answered)} answers of {out['n_participants']} participants; "
        f"{len(answered) - len(known)} of them are to faces with no right answer (random "
        "faces, file rows without a label) or to stand-ins for others' faces (fallback): "
        "those are not in the accuracies. The pooled accuracies and confusion matrices "
        "describe the answers; every test below is over participants."
    )
    report.table(by_source, "categorisation_by_source", "Accuracy by face source (pooled)")
    _long(
        report,
        accuracy_by_source(responses),
        "categorisation_participants",
        "Accuracy on own and others' faces per participant",
    )


def _confusion(responses: pd.DataFrame, report: Content) -> None:
    from emogen.analysis.categorisation_figures import confusion_figure

    table = rec.confusion_table(responses)
    report.table(
        table,
        "categorisation_confusion",
        "Confusion matrices (intended × label; counts and row proportions), over all faces "
        "with an intended emotion and per face source; random faces: the labels given to them",
    )
    if table.empty:
        return
    path = confusion_figure(table, report.figures / "categorisation_confusion.png")
    report.figure(
        path,
        "Confusion matrices: share of each intended emotion's faces given each label "
        "(cell: count), per face source; random faces have no intended emotion (one row: "
        "their labels).",
    )


def _hit_rates(
    responses: pd.DataFrame, report: Section, out: dict[str, Any], opts: AnalysisOptions
) -> None:
    hu = rec.unbiased_hit_rates(responses)
    if hu.empty:
        report.paragraph("Unbiased hit rates: no answer to a face with an intended emotion.")
        return
    tests = rec.hu_tests(hu, opts.alpha)
    _long(
        report,
        hu,
        "categorisation_hit_rates",
        "Unbiased hit rate Hu and chance pc per participant × emotion",
    )
    report.table(
        tests, "categorisation_hit_rate_tests", "Hu against chance per emotion (over participants)"
    )
    out["hit_rates"] = tests.to_dict(orient="records")
    for row in out["hit_rates"]:
        name = f"categorisation.hit_rates[{row['emotion']}]"
        if not np.isfinite(row["p"]):
            reason = f"{row['n_participants']} participant(s), or no spread: no t"
            report.not_run(name, reason, row, n=row["n_participants"])
            continue
        report.add_test(
            name,
            row,
            test="one-sample t (arcsin√Hu − arcsin√pc)",
            p=row["p"],
            n=row["n_participants"],
            statistic=row["t"],
            df=row["n_participants"] - 1,
            estimate=row["mean_difference"],
            interval=(row["ci_low"], row["ci_high"]),
            level=0.95,
        )
    above = ", ".join(tests.loc[tests["above_chance"], "emotion"]) or "none"
    report.paragraph(
        "Unbiased hit rates (Wagner 1993): per participant and emotion, Hu = hits² / (faces of "
        "the emotion × uses of its label) and chance pc = (faces / N) × (uses / N), over the "
        "participant's answers to faces with an intended emotion (own, others', file). Test: "
        "per emotion, a one-sample t over participants (the participant is the unit) of "
        "arcsin√Hu − arcsin√pc, Holm-corrected over emotions at α = "
        f"{opts.alpha}; assumes independent participants and a roughly normal mean difference "
        f"after the arcsine transform. Above chance: {above}."
    )


def _sources(
    responses: pd.DataFrame, report: Section, out: dict[str, Any], opts: AnalysisOptions
) -> None:
    per = rec.accuracy_per_participant(responses)
    pairs = rec.source_comparisons(per, opts.alpha)
    _long(report, per, "categorisation_accuracy", "Accuracy per participant and face source")
    if not pairs.empty:
        report.table(
            pairs,
            "categorisation_source_tests",
            "Accuracy between face sources (paired over participants)",
        )
        report.paragraph(
            "Accuracy by source: each participant's share of correct answers per source "
            "(own, others', file faces; fallback and random faces have no right answer); "
            "each pair of sources compared by a paired t over the participants with both "
            "(the participant is the unit; CI of the mean difference; Holm-corrected over "
            "pairs; assumes independent participants and a roughly normal mean difference)."
        )
    adv = own_advantage(responses)
    out["own_advantage"] = adv
    name = "categorisation.own_advantage"
    if np.isnan(adv["ci_low"]):
        report.not_run(name, adv["note"], adv, n=adv["n_participants"])
        report.paragraph(f"Own- against other-face accuracy: {adv['note']}.")
        return
    report.add_test(
        name,
        adv,
        test=adv["test"],
        p=adv["p"],
        n=adv["n_participants"],
        statistic=adv["t"],
        df=adv["n_participants"] - 1,
        estimate=adv["difference"],
        interval=(adv["ci_low"], adv["ci_high"]),
        level=adv["confidence"],
        effect=("dz", adv["dz"], adv["dz_low"], adv["dz_high"]),
    )
    report.paragraph(
        f"Own- against other-face accuracy ({adv['test']}; the participant is the unit, "
        f"n = {adv['n_participants']}; fallback faces left out): own "
        f"{adv['accuracy_own']:.3f}, others' {adv['accuracy_other']:.3f}, difference "
        f"{adv['difference']:+.3f}, 95% CI [{adv['ci_low']:+.3f}, {adv['ci_high']:+.3f}], "
        f"t = {adv['t']:.2f}, p = {adv['p']:.3g}; dz = {adv['dz']:.2f} [{adv['dz_low']:.2f}, "
        f"{adv['dz_high']:.2f}] (noncentral-t interval)."
    )
