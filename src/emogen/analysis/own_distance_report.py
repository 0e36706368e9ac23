"""The report's subsection on the own-distance model (Binetti et al. 2022;
:mod:`emogen.analysis.categorisation_models`): the primary conditional logit (two-way clustered
intervals, tested by the shuffled-prototype permutation over participants), then the secondary
GEE and two-stage tests and the permutation's details. A fit without an
estimate is named with its reason (never a NaN in the text or the JSON); a fallback is named
beside the estimate it gave.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.analysis.analyse_options import AnalysisOptions

if TYPE_CHECKING:
    from emogen.analysis.categorisation_models import OwnDistance
    from emogen.analysis.people import People
    from emogen.analysis.report import Content
    from emogen.analysis.results import Section

#: Shuffles (derangements of participants) of the report's shuffled-prototype control.
SHUFFLES = 199


def own_distance_section(
    people: People, report: Section, out: dict[str, Any], opts: AnalysisOptions
) -> None:
    """Fit the own-distance model of ``people`` and write it (``out["own_distance"]``)."""
    from emogen.analysis import categorisation_models as cm

    res = cm.own_distance(people, rng=np.random.default_rng(opts.seed), n_shuffles=SHUFFLES)
    report.heading("Own faces predict labels (Binetti et al. 2022)", level=3)
    if isinstance(res, str):
        report.paragraph(f"No own-distance model: {res}.")
        out["own_distance"] = {"note": res}
        report.not_run("categorisation.own_distance.primary", res)
        return
    tests = {
        "primary": res.primary,
        "gee": res.gee,
        "two_stage": res.two_stage,
        "control": {k: v for k, v in res.control.items() if k != "control"},
    }
    out["own_distance"] = tests | {"fit_problems": fit_problems(tests)}
    for name, t in tests.items():
        _register(report, f"categorisation.own_distance.{name}", t)
    _tables(report, res)
    _method(report, res, opts)
    _primary(report, res.primary)
    _secondary(report, res, opts)
    _problems(report, out["own_distance"]["fit_problems"])
    _figure(report, res)


#: Each test's p, statistic and estimate keys in its record (the two-stage test's p is its t's).
_KEYS = {
    "primary": ("p", "t", "contrast"),
    "gee": ("p", "z", "contrast"),
    "two_stage": ("p_t", "t", "mean_contrast"),
    "control": ("p", None, None),
}


def _register(report: Section, name: str, t: dict[str, Any]) -> None:
    """The test ``t`` (a record of ``out["own_distance"]``) in the report's plan: run, or not
    run with its fit's reason."""
    p_key, stat_key, est_key = _KEYS[name.rsplit(".", 1)[1]]
    p = t.get(p_key)
    if t.get("status") == "failed" or p is None or not np.isfinite(p):
        reason = t.get("reason") or "no p-value"
        report.not_run(name, f"fit {t.get('status', 'failed')}: {reason}", t)
        return
    has_ci = "ci_low" in t and est_key is not None
    report.add_test(
        name,
        t,
        test=str(t.get("test", stat_key)),
        p=p,
        n=t.get("n_participants"),
        statistic=None if stat_key is None else t[stat_key],
        df=t.get("df"),
        unit=str(t.get("unit", "participant")),
        estimate=None if est_key is None else t[est_key],
        interval=(t["ci_low"], t["ci_high"]) if has_ci else None,
        level=t.get("confidence"),
        warnings=tuple(t.get("warnings", ())),
        fit=str(t.get("status", "ok")),
    )


def fit_problems(tests: dict[str, dict[str, Any]]) -> list[dict[str, str]]:
    """Every fit that failed or fell back: which test, what happened, the reason."""
    rows = []
    for name, t in tests.items():
        if t.get("status") == "failed":
            rows.append({"test": name, "outcome": "no estimate", "reason": t["reason"]})
        rows += [{"test": name, "outcome": "warning", "reason": w} for w in t.get("warnings", [])]
    return rows


def _tables(report: Content, res: OwnDistance) -> None:
    for table, name, caption in (
        (
            res.table,
            "categorisation_model_long",
            "The own-distance model's long table (answer × offered label)",
        ),
        (
            res.slopes,
            "categorisation_model_slopes",
            "Per-participant maximum-likelihood "
            "slopes (two-stage model, first stage; log-odds per unit gene distance; NA: no "
            "estimate, with the reason)",
        ),
    ):
        more = len(table) > 8
        note = f" (first 8 of {len(table)} rows; all in tables/{name}.csv)" if more else ""
        report.table(table.head(8), name, caption + note, data=table)


def _method(report: Content, res: OwnDistance, opts: AnalysisOptions) -> None:
    p = res.primary
    report.paragraph(
        f"For each answer to a face the participant did not make (others' and random faces: "
        f"{p['n_answers']} answers of {p['n_participants']} participants to {p['n_stimuli']} "
        "faces), d_own is the gene-space Euclidean distance from the test face to the mean of "
        "the participant's own final faces of each offered label, and d_ref the same distance "
        "to the faces of a reference participant (a random derangement of participants: "
        f"nobody is their own reference; seed {opts.seed}; answers to faces the reference made "
        "are left out). Own faces are not test faces here: one's other faces of an emotion "
        "were made toward the same internal face, so they would predict an own face's label "
        "even without any labeller effect. Everyone's faces of an emotion lie near the "
        "population's, so d_own alone predicts labels without individual prototypes; the "
        "individual effect is d_own beyond d_ref — the contrast of the two slopes (negative: "
        "one's own faces predict one's labels better)."
    )


def _slopes(t: dict[str, Any]) -> str:
    return (
        f"slope on d_own {t['slope_own']:+.2f} [{t['ci_low_own']:+.2f}, {t['ci_high_own']:+.2f}]"
        f" per unit distance (odds ratio {np.exp(t['slope_own'] / 10):.3g} per 0.1), on d_ref "
        f"{t['slope_ref']:+.2f} [{t['ci_low_ref']:+.2f}, {t['ci_high_ref']:+.2f}]"
    )


def _say(report: Content, head: str, t: dict[str, Any], body: Callable[[], str]) -> None:
    """One test's paragraph: ``head`` then its result, or that it was not estimated and why."""
    text = body() if t["status"] == "ok" else f"**not estimated** — {t['reason']}."
    report.paragraph(head + text)


def _primary(report: Content, p: dict[str, Any]) -> None:
    head = (
        "Primary test — conditional logit (the label chosen among those offered; McFadden "
        "1974) on d_own, d_ref and one constant per label, pooled over answers; intervals from "
        "two-way cluster-robust standard errors over participants and faces (Cameron, Gelbach "
        "& Miller 2011; a face shown to many judges is an item); the test a permutation over "
        "participants: the slope on d_own against the same slope with every participant's own "
        "faces replaced by another participant's (one-sided: own faces predict labels better), "
        "valid whatever the distances' effect shape; assumes a logit-linear effect for the "
        "estimates: "
    )
    _say(
        report,
        head,
        p,
        lambda: (
            f"{_slopes(p)}; contrast own − ref {p['contrast']:+.2f}, 95% CI "
            f"[{p['ci_low']:+.2f}, {p['ci_high']:+.2f}]; permutation p = {p['p']:.3g} "
            f"({p['n_shuffles']} shuffles; two-way t({p['df']}) = {p['t']:.2f}, two-sided p = "
            f"{p['p_two_way']:.3g}; converged in {p['iterations']} Newton steps; "
            f"{p['n_participant_clusters']} participants, {p['n_stimulus_clusters']} faces)."
        ),
    )


def _secondary(report: Content, res: OwnDistance, opts: AnalysisOptions) -> None:
    g, two, ctl = res.gee, res.two_stage, res.control
    _say(
        report,
        "Secondary — GEE (binomial, logit link; answer × offered label, chosen 0/1, on d_own, "
        "d_ref and one intercept per label; robust SE over participants only, faces not "
        "clustered): ",
        g,
        lambda: (
            f"{g['working_correlation']} working correlation ({g['correlation']:+.3f}); "
            f"{_slopes(g)}; contrast {g['contrast']:+.2f}, 95% CI [{g['ci_low']:+.2f}, "
            f"{g['ci_high']:+.2f}], z = {g['z']:.2f}, p = {g['p']:.3g}."
        ),
    )
    _say(
        report,
        "Secondary — two-stage (per participant the maximum-likelihood conditional logit on "
        "d_own and d_ref, no penalty; then over participants, the unit; the Wilcoxon test "
        "assumes a symmetric distribution of contrasts): ",
        two,
        lambda: (
            f"mean contrast {two['mean_contrast']:+.2f}, 95% CI [{two['ci_low']:+.2f}, "
            f"{two['ci_high']:+.2f}], t = {two['t']:.2f}, p = {two['p_t']:.3g}; Wilcoxon "
            f"signed-rank p = {two['p_wilcoxon']:.3g} (n = {two['n_participants']})."
        ),
    )
    _say(
        report,
        "The primary test's permutation in detail (the pooled conditional-logit slope on "
        "distance to one's own faces against the same slope with each participant's faces "
        f"replaced by another's; {ctl['n_shuffles']} derangements, seed {opts.seed}; assumes "
        "participants exchangeable under the null): ",
        ctl,
        lambda: (
            f"own {ctl['slope_own']:+.2f}; shuffled {ctl['control_mean']:+.2f} on average "
            f"(95% of shuffles in [{ctl['control_low']:+.2f}, {ctl['control_high']:+.2f}]); "
            f"one-sided p = {ctl['p']:.3g}."
        ),
    )


def _problems(report: Content, problems: list[dict[str, str]]) -> None:
    if not problems:
        report.paragraph("Every fit of the own-distance model converged, with no fallback.")
        return
    report.paragraph(
        "Fits that failed or fell back (a failed fit gives no estimate; a fallback's estimate "
        "is the one shown above):"
    )
    report.bullets([f"{p['test']}: {p['outcome']} — {p['reason']}" for p in problems])


def _figure(report: Content, res: OwnDistance) -> None:
    from emogen.analysis.categorisation_figures import own_distance_figure

    path = own_distance_figure(res, report.figures / "categorisation_own_distance.png")
    report.figure(
        path,
        "A: per participant, the share of answers whose label is the offered emotion "
        "with the nearest mean face among one's own faces (y) and among the reference "
        "participant's (x); above the diagonal, one's own faces predict one's labels better "
        "(descriptive). B: the shuffled control's slopes (derangements of participants) and "
        "the slope with one's own faces.",
    )
