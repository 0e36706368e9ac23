"""The report's Section IV-C parts: initialisation, bias and repeatability, activation ranges,
target complexity and GA noise, selection pressure."""

from __future__ import annotations

from emogen.analysis import paper, plots
from emogen.analysis.replication.bias_repeatability import BiasRepeatability
from emogen.analysis.replication.ga_settings import (
    ActivationRanges,
    ComplexityNoise,
    SelectionPressure,
)
from emogen.analysis.replication.initialisation import Initialisation
from emogen.analysis.replication.write_report import FaceFigures
from emogen.analysis.report import Report


def write_initialisation(r: Report, res: Initialisation, figures: FaceFigures) -> None:
    r.heading("Initialisation: fixed against protocol (Figs. 14–17)")
    r.paragraph(
        "Target 1, CD observer. Fixed initialisation draws one of our three packaged sets at "
        "random per run (none contains jawOpen, so the initial bias is 1.0, as for the paper's "
        "first row of Table III); protocol initialisation is the default. Then again with three "
        "selections in every generation (Figs. 16–17)."
    )
    r.table(
        res.convergence,
        "init_convergence",
        "Elite CD error μ ± σ; KL between consecutive generations",
    )
    sims, kls = res.conditions, res.kl
    for sel, fig, kfig in (("default", "fig14", "fig15"), ("three", "fig16", "fig17")):
        panels = {f"{i} init": sims[(i, sel)].errors for i in ("fixed", "protocol")}
        what = "paper schedule" if sel == "default" else "three selections per generation"
        r.figure(
            plots.generation_distributions(panels, r.figures / f"{fig}_init_{sel}.png"),
            f"{fig.replace('fig', 'Fig. ')} analogue ({what}): per-generation CD error, target 1.",
        )
        r.figure(
            plots.kl_curves(
                {f"{i} init": kls[(i, sel)] for i in ("fixed", "protocol")},
                r.figures / f"{kfig}_kl_{sel}.png",
            ),
            f"{kfig.replace('fig', 'Fig. ')} analogue ({what}): KL(P_g ‖ P_g−1) of the error "
            "distributions.",
        )
    r.table(res.kl_table, "kl_init", "KL(P_g ‖ P_g−1) per generation [nats]", index=True)
    figures.heatmaps(
        r,
        "fig14_16_mean_faces",
        [
            (
                f"{i} init, {'3 sel.' if s == 'three' else 'paper sel.'}",
                sims[(i, s)].mean_face,
                sims[(i, s)].target,
            )
            for (i, s) in sims
        ],
        "Figs. 14 and 16 analogue: distance (cm) of the mean final face to target 1.",
    )


def write_bias_repeatability(r: Report, res: BiasRepeatability) -> None:
    r.heading("Target bias and repeatability (Table III)")
    avg, active = res.average_target, res.active_per_face
    r.paragraph(
        "Bias = CD of the best initial option to the target (1.0: none). The 'average' target is "
        "our analogue of the paper's average expression of 80 user trials: the mean final face of "
        "80 simulated-participant trials evolving happy (40 from fixed, 40 from protocol "
        f"initialisation; {sum(v > 0.1 for v in avg.values())} shapes above 0.1). Bins: shares of "
        "all pairs of final elites by their CD. Fixed sets: ours no. 1 (simple) and no. 3 "
        f"(complex), {active[1]:.1f} and {active[3]:.1f} active "
        f"shapes per face (the paper's: {paper.FIXED_ACTIVATIONS[1]} and {paper.FIXED_ACTIVATIONS[3]})."
    )
    r.table(
        res.table,
        "table_iii",
        "Table III analogue: bias and inter-sample CD bins of the final elites",
    )
    r.figure(
        plots.bins(res.bins_table, r.figures / "table_iii_bins.png"),
        "Table III analogue: repeatability bins.",
    )


def write_activation_ranges(r: Report, res: ActivationRanges) -> None:
    r.heading("Blendshape activation in the initialisation (Table IV)")
    r.paragraph(
        "Protocol initialisation with 1–3, 3–8 (default) or 8–16 active genes per face "
        "(capped at an emotion's building blocks); μ, σ of the elite CD error at "
        "generations 0 and 10."
    )
    r.table(res.table, "table_iv", "Table IV analogue")


def write_complexity_noise(r: Report, res: ComplexityNoise, figures: FaceFigures) -> None:
    r.heading("Target complexity and GA noise (Table V, Fig. 18)")
    sims = res.conditions
    r.table(res.table, "table_v", "Table V analogue: final CD error by target complexity")
    r.figure(
        plots.generation_distributions(
            {t: s.errors for t, s in sims.items()}, r.figures / "fig18_convergence.png"
        ),
        "Fig. 18 analogue: per-generation CD error for targets of increasing complexity.",
    )
    r.figure(
        plots.final_distributions(
            {t: s.final_errors for t, s in sims.items()}, r.figures / "table_v_final.png"
        ),
        "Final CD error distributions (the GA noise) by target.",
    )
    figures.heatmaps(
        r,
        "fig18_mean_faces",
        [(t, s.mean_face, s.target) for t, s in sims.items()],
        "Fig. 18 analogue: distance (cm) of the mean final face to each target.",
    )


def write_selection_pressure(r: Report, res: SelectionPressure) -> None:
    r.heading("Selection pressure: fitness-ranked (classical) against EmoGen's GA")
    r.paragraph(
        "The classical variant ranks the whole population by CD to the target; the fittest pairs "
        "breed once each, two children replacing both parents (docs/ga.md). Same seeds, same "
        "targets. Cohen's d of the final errors (classical − EmoGen): |d| < 0.2 is negligible."
    )
    r.table(res.table, "selection_pressure", "Final CD error, EmoGen against classical")
