"""The per-gene section of the report of people: emotion and group tests per gene, the
blendshape → FACS action-unit approximations, and the genes × contrasts heat map."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.analysis import plots
from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.facs import CAVEAT, facs_table, gene_label
from emogen.analysis.genes import USED, GeneTestOptions, emotion_gene_tests, group_gene_tests
from emogen.analysis.people import People
from emogen.analysis.report import Content
from emogen.analysis.results import Section

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

MIN_PARTICIPANTS = 3


def genes_section(
    people: People, folder: Path, opts: AnalysisOptions, model: FaceModel | None
) -> Section:
    """Per-gene inference (see :mod:`emogen.analysis.genes`) into the section; headline numbers
    into ``analysis.json``'s ``genes``."""
    report = Section(folder)
    del model
    report.heading("Per-gene inference")
    if people.n_participants < MIN_PARTICIPANTS:
        report.paragraph(
            f"Per-gene tests need >= {MIN_PARTICIPANTS} participants; this study has "
            f"{people.n_participants}."
        )
        return report
    rng = np.random.default_rng(opts.seed)
    gopts = GeneTestOptions(level=1 - opts.alpha)
    report.paragraph(
        "**Unit: the participant.** Each participant's final faces are averaged per emotion (over "
        "identities and repetitions) before any test. Statistic: the studentised mean difference "
        "(t), its p-value from permutations, never from the t distribution (genes are bounded in "
        "[0, 1] and often exactly 0). Family-wise error: max-T over every gene × contrast of a "
        "table (`p_maxt`, Westfall & Young 1993); false discovery rate: Benjamini–Hochberg over "
        f"the same family (`q_bh`). α = {opts.alpha:g}; seed {opts.seed}; "
        f"{gopts.permutations} permutations (exact enumeration when fewer exist). Effect: the "
        f"mean difference (gene units) with a {gopts.level:.0%} interval over participants that "
        "inverts a permutation test (emotions: sign flips of the paired differences; groups: "
        "relabellings, of a shift; Student's or Welch's t where too few participants allow no "
        "finite one, named in `ci_method`; coverage at 8 participants per group in "
        "docs/analysis.md); `used_*`: the share of participants whose "
        f"mean of the gene exceeds {USED:g}."
    )
    report.table(
        facs_table(people.genes),
        "genes_facs",
        "Blendshape genes and the FACS action units they approximate (not AUs).",
    )
    report.paragraph(CAVEAT)
    out: dict[str, Any] = {}
    if len(people.emotions) < 2:
        report.paragraph("Emotion contrasts: the study has one emotion, so there is none to test.")
    else:
        emo = emotion_gene_tests(people, gopts, rng=rng)
        report.paragraph(
            "**Emotions** (within participants): every pair of emotions; under H0 the two are "
            "exchangeable within each participant, so the sign of each participant's difference "
            "is flipped at random (one flip shared by all genes of a contrast, independent flips "
            "across contrasts: exact per contrast, conservative across them). Assumes "
            "participants independent of one another."
        )
        report.table(
            _shown(emo, "contrast"),
            "genes_emotion_tests",
            "Genes that differ between emotions (FWER- or FDR-significant rows; the "
            "CSV has every gene × contrast).",
            data=emo,
        )
        path = heatmap(emo, report.figures / "genes_emotions", alpha=opts.alpha)
        report.figure(
            path,
            "Participant-mean difference per gene (rows, ≈ action unit) and pair "
            "of emotions (columns). * BH q < α; ** max-T p < α (FWER).",
        )
        out["emotion_maxt"] = int(emo["significant_maxt"].sum())
        out["emotion_bh"] = int(emo["significant_bh"].sum())
        out["emotion_tests"] = len(emo)
    _groups(people, report, gopts, rng, out)
    report.data["genes"] = out
    return report


def _groups(
    people: People, report: Content, gopts: GeneTestOptions, rng: np.random.Generator, out: dict
) -> None:
    if "group" not in people.participant_columns:
        report.paragraph("Group contrasts: no participant table with a `group` column was given.")
        return
    sizes = people.faces.groupby("participant_id")["group"].first().value_counts()
    if len(sizes) < 2 or (sizes < 2).any():
        report.paragraph(
            f"Group contrasts: need >= 2 groups of >= 2 participants; got {sizes.to_dict()}."
        )
        return
    grp = group_gene_tests(people, gopts, rng=rng)
    report.paragraph(
        "**Groups** (between participants), per emotion and gene: Welch's t of the groups' "
        "participant means, its p-value from relabelling participants at random (one relabelling "
        "shared by all genes and emotions; studentised, so valid when the groups' variances "
        "differ). More than two groups: every pair, max-T within the pair, Bonferroni over pairs. "
        "Assumes participants independent and exchangeable between groups under H0."
    )
    report.table(
        _shown(grp, "emotion"),
        "genes_group_tests",
        "Genes that differ between groups (significant rows; the CSV has every row).",
        data=grp,
    )
    out["group_maxt"] = int(grp["significant_maxt"].sum())
    out["group_bh"] = int(grp["significant_bh"].sum())
    out["group_tests"] = len(grp)


def _shown(table: pd.DataFrame, by: str) -> pd.DataFrame:
    """The significant rows (or the five smallest p when none), the columns a reader needs."""
    hits = table[table["significant_bh"] | table["significant_maxt"]]
    if hits.empty:
        hits = table.nsmallest(5, "p_perm")
    cols = ["gene", "facs_code", by, "difference", "ci_low", "ci_high"]
    cols += [c for c in ("used_a", "used_b") if c in table.columns]
    return hits[[*cols, "t", "p_perm", "p_maxt", "q_bh"]].reset_index(drop=True)


def heatmap(table: pd.DataFrame, path: Path, *, alpha: float) -> Path:
    """Genes × contrasts heat map of mean differences with significance marks."""
    genes = list(dict.fromkeys(table["gene"]))
    contrasts = list(dict.fromkeys(table["contrast"]))

    def cells(values: str) -> np.ndarray:
        wide = table.pivot(index="gene", columns="contrast", values=values)
        return wide.loc[genes, contrasts].to_numpy(np.float64)

    grid, q, pm = cells("difference"), cells("q_bh"), cells("p_maxt")
    fig = plots.new_figure(1.6 + 0.75 * len(contrasts), 1.2 + 0.24 * len(genes))
    ax = fig.add_subplot(1, 1, 1)
    lim = max(float(np.nanmax(np.abs(grid))), 1e-6)
    im = ax.imshow(grid, cmap="PuOr_r", vmin=-lim, vmax=lim, aspect="auto")
    for (i, j), _ in np.ndenumerate(grid):
        mark = "**" if pm[i, j] < alpha else "*" if q[i, j] < alpha else ""
        if mark:
            dark = abs(grid[i, j]) > 0.6 * lim
            ax.text(
                j, i, mark, ha="center", va="center", fontsize=7, color="white" if dark else "black"
            )
    ax.set_xticks(range(len(contrasts)), contrasts, rotation=40, ha="right", fontsize=7)
    ax.set_yticks(range(len(genes)), [gene_label(g) for g in genes], fontsize=7)
    cbar = fig.colorbar(im, ax=ax, shrink=0.6)
    cbar.set_label("mean difference (gene units, a − b)", fontsize=7)
    ax.set_title("Per-gene emotion contrasts (participant means)", fontsize=9)
    return plots.save_figure(fig, path)
