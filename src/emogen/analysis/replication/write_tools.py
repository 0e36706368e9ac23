"""The report's checks of our tools: the spread test and separability on simulated
participants, and the power analysis."""

from __future__ import annotations

from emogen.analysis import plots
from emogen.analysis.replication.analysis_tools import ParticipantTools, PowerStudy
from emogen.analysis.replication.settings import ReplicateSettings
from emogen.analysis.report import Report
from emogen.analysis.separability_figure import separability_figure


def write_participant_tools(r: Report, res: ParticipantTools, settings: ReplicateSettings) -> None:
    r.heading("The analysis tools on simulated participants")
    k, n_control = res.groups, res.group_size
    r.paragraph(
        f"The {settings.participants} simulated participants per emotion of the empirical-metrics "
        "section, final faces only. Each evolved their own target (core building blocks of the "
        "emotion, plus some optional ones), so a group's spread holds real between-participant "
        "differences on top of GA noise and their own choice noise (T = "
        f"{settings.participant_noise}). The null simulates the same choice noise, so the test "
        "flags a group only where the participants' differences exceed what GA noise and "
        "choice noise make around ONE shared target; small differences stay within it (a null "
        "without the choice noise flagged every group, and one-target groups too). As a check "
        f"of the test itself, {k} control groups of {n_control} runs toward target 1 (sparse) "
        f"and {k} toward target 2 (one shared target each, the same choice noise, fresh seeds) "
        "should mostly not exceed the noise: the share that does is the test's false-alarm "
        "rate (nominal 5%; tests/analysis/test_noise_calibration.py measures it on 100 groups "
        "per noise level)."
    )
    r.table(
        res.spread,
        "spread_test_participants",
        "Spread of each emotion group against simulated GA noise (one-sided, α = 0.05)",
    )
    r.figure(
        plots.spread(res.spread, r.figures / "spread_participants.png"),
        "Mean proxy error per group against the GA noise expected at the same n.",
    )
    r.table(
        res.candidates,
        "spread_candidates_participants",
        "Latent-target candidates (τ: weights below τ × max zeroed, then refined)",
    )
    r.table(
        res.controls,
        "spread_test_controls",
        "Control groups (one shared target each): the test's false alarms",
    )
    sep, sep90 = res.separability, res.separability_90
    r.paragraph(
        f"Separability of the four emotions' final faces: accuracy {sep.accuracy:.1%} in 2 PCA "
        f"components, {sep90.accuracy:.1%} in {sep90.n_pca} (90% of the variance); ARI "
        f"{sep.ari:.2f} / {sep90.ari:.2f}."
    )
    r.table(
        sep.confusion,
        "emotions_confusion",
        "GMM classification of the emotions' final faces (2 components)",
        index=True,
    )
    r.figure(
        separability_figure(
            sep,
            r.figures / "emotions_separability.png",
            title=f"four emotions: accuracy {sep.accuracy:.0%}",
        ),
        "Simulated participants' final faces in PCA components 1–2, by emotion.",
    )


def write_power(r: Report, res: PowerStudy, s: ReplicateSettings) -> None:
    r.heading("Power analysis")
    power = res.result
    r.paragraph(
        "Two groups whose happy prototypes differ by raised inner brows (browInnerUp 0.4 added; "
        f"CD between the prototypes {res.prototype_cd:.3f}). Each participant holds "
        f"the prototype plus N(0, {res.participant_sd}²) per gene and makes one face (10 "
        f"generations, choice noise T = {s.participant_noise}); the test compares the groups' "
        f"mean faces by CD with {s.power_permutations} permutations; {s.power_replicates} "
        "simulated experiments per n, each with fresh participants (none shared between "
        "experiments at one n). The false-positive column is the same test on null experiments "
        "from the same simulated participants (both groups one prototype): it should stay at "
        "α = 0.05 within its standard error. `emogen power` runs this for any two prototypes."
    )
    r.table(power.curve, "power_curve", "Power against participants per group (α = 0.05)")
    r.figure(
        plots.power_curve(
            power.curve, r.figures / "power.png", target=0.8, n_required=power.n_required
        ),
        "Power curve; dashed: 80%.",
    )
    req = power.required
    if power.n_required is None or req is None:
        r.paragraph(f"80% power is not reached within {s.power_max_n} participants per group.")
    else:
        how = (
            "on the fitted curve (logistic in log n, binomial maximum likelihood; its χ² "
            f"goodness of fit against the simulated points: p = {req.fit_p:.2g})"
            if req.method == "fit"
            else "by interpolating the simulated points in log n (the logistic fit misfits "
            f"them: χ² p = {req.fit_p:.2g})"
        )
        hi = "beyond the simulated n" if req.hi is None else req.hi
        r.paragraph(
            f"**{power.n_required} participants per group** (95% CI {req.lo}–{hi}, a "
            f"parametric bootstrap of the simulated points) reach 80% power {how}. The "
            f"smallest simulated n whose own estimate reached it: {power.n_observed}."
        )
    fp = power.curve["false_positive"]
    r.paragraph(
        f"False-positive rate over the curve: {fp.min():.3f}–{fp.max():.3f} (mean "
        f"{fp.mean():.3f}; α = 0.05; standard error of each ≈ "
        f"{float(power.curve['fp_se'].mean()):.3f})."
    )
