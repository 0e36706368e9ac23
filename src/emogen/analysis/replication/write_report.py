"""The replication report's frame: the introduction, rendered face figures, and the closing
table of every finding with the run's timings."""

from __future__ import annotations

import platform
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis.replication.findings import VERDICTS
from emogen.analysis.replication.settings import ReplicateSettings
from emogen.analysis.replication.verdicts import Combined
from emogen.analysis.report import Report

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

Panels = list[tuple[str, np.ndarray, np.ndarray]]  # (label, face, reference)


@dataclass(frozen=True, eq=False)
class FaceFigures:
    """Rendered figures of faces (when ``render``) on ``model``."""

    model: FaceModel
    render: bool

    def heatmaps(
        self, report: Report, name: str, panels: Panels, caption: str, columns: int = 4
    ) -> pd.DataFrame | None:
        """A sheet of mean-face heatmaps (label, face, reference); the per-panel distances, or
        None when not rendering."""
        if not self.render:
            return None
        from emogen.analysis.face_sheets import Panel, heatmap_sheet

        path = report.figures / f"{name}.png"
        stats = heatmap_sheet(self.model, [Panel(*p) for p in panels], path, columns=columns)
        report.figure(path, caption)
        return stats

    def faces(
        self, report: Report, name: str, weights: np.ndarray, labels: list[str], caption: str
    ) -> None:
        """A sheet of faces (when rendering)."""
        if not self.render:
            return
        from emogen.analysis.face_sheets import face_sheet

        report.figure(
            face_sheet(self.model, weights, labels, report.figures / f"{name}.png"), caption
        )


def write_intro(report: Report, model: FaceModel, s: ReplicateSettings) -> int:
    """The opening paragraphs; returns where the at-a-glance summary goes."""
    report.paragraph(
        "The experiments of the paper's Section IV (Tables I–V, Figs. 6–18), run on our model "
        f"(`{model.name}`, model hash `{model.model_hash[:16]}…`, {model.n_shapes} shapes, "
        f"{len(model.rig.gene_names(True))} genes) with our GA, each finding printed beside the "
        "paper's numbers with a verdict by a written rule: **holds**, **partly** (in part, or "
        "only qualitatively), **differs** or **inconclusive** (the evidence does not decide, or "
        "the seeds disagree). The closing table lists them all with the rules."
    )
    report.bullets(
        [
            f"{s.runs} simulated runs per condition (the paper: 500), 10 generations, the paper's "
            "selection schedule (2, then 4 in generations 1–5, then 5), protocol initialisation "
            "with 3–8 active genes, a noiseless CD observer — unless a section says otherwise.",
            f"{s.seeds} independent seeds ({', '.join(map(str, s.seed_list))}); within a seed every "
            "condition uses the same seed (conditions differ only by their settings). Tables "
            "and figures show the first seed; every verdict combines all seeds."
            + (
                " `--quick` has its own seeds: its runs are not a subset of the full run's."
                if s.quick
                else ""
            ),
            "Simulations run **uncorrected** (no Section III-A correctives): the paper's "
            "Section IV simulations evolve core weights; `emogen simulate --correct` runs with "
            "them.",
            "The paper's empirical metrics were trained on **9,592 faces made by 240 human "
            f"participants**; we have none. Ours are trained on {s.participants * 40:,} faces made by "
            f"{s.participants} **simulated participants** evolving the four emotions (happy, sad, "
            "angry, fearful) toward their own internal targets with choice noise — see that section.",
            "Our model is not the paper's: ICT-FaceKit's 57 shapes with a 30-gene space (the paper: "
            "149 shapes, 45–55 unique core shapes), so absolute numbers differ; the findings are "
            "about orderings and comparisons, and the verdicts judge those.",
        ]
    )
    return len(report.blocks)


def write_closing(
    report: Report,
    combined: list[Combined],
    timings: dict[str, float],
    *,
    glance_at: int,
    seconds: float,
    version: str,
    settings: ReplicateSettings,
    provenance: dict[str, str],
) -> None:
    """The findings table (and its tally, both ways, at ``glance_at``), the rules, the paper
    findings outside the tally and our own checks apart, the change table, the run's
    provenance and timings."""
    paper = [c for c in combined if c.finding.paper_finding and not c.finding.outside]
    apart = [c for c in combined if c.finding.paper_finding and c.finding.outside]
    ours = [c for c in combined if not c.finding.paper_finding]
    report.heading("Findings: the paper beside ours")
    tally = tally_both_ways([c.verdict for c in paper])
    k = settings.seeds
    report.paragraph(_how_decided(len(paper), k, provenance["seeds"], tally))
    report.insert_paragraph(
        glance_at,
        f"**At a glance:** {len(paper)} findings of the paper checked on our model over {k} "
        f"seeds: {tally}. The closing table lists every one with the paper's numbers, ours, "
        f"the rule and the verdict; {len(apart)} model-specific, oracle or repeated findings "
        "and our own checks are reported apart.",
    )
    report.paragraph(
        "**Multiple comparisons.** The table makes "
        f"{len(combined)} comparisons. They are **exploratory**: the rules are descriptive "
        "(orderings, thresholds, 95% intervals at the per-comparison level), no family-wise or "
        "false-discovery correction is applied, and a single 'holds' or 'differs' should not be "
        "read as a confirmed test result."
    )
    report.table(_rules_table(), "verdict_rules", "The verdict rules")
    report.table(
        _rows(paper),
        "findings",
        "Every finding, with the paper's numbers and ours",
        data=_records(paper),
    )
    if apart:
        report.heading("Paper findings outside the tally", level=3)
        report.table(
            _rows(apart, reason=True),
            "outside_tally",
            "Model-specific levels, oracle checks and repeated events: reported, not counted",
            data=_records(apart),
        )
    _write_changed(report, combined, settings)
    if ours:
        report.heading("Our own checks (outside the tally)", level=3)
        report.table(
            _rows(ours),
            "our_checks",
            "Checks of our tools, not paper findings",
            data=_records(ours),
        )
    report.heading("Run", level=3)
    report.paragraph(
        f"EmoGen {version}, Python {platform.python_version()}, {platform.machine()}; "
        f"{'quick' if settings.quick else 'full'} run in {seconds:.0f} s. Every simulation "
        "runs without the Section III-A correctives (uncorrected faces): the GA, the observers "
        "and the metrics act on the core weights; the paper does not say whether its Section "
        "IV simulations applied them."
    )
    report.bullets([f"{key}: `{value}`" for key, value in provenance.items()])
    timing = pd.DataFrame({"experiment": list(timings), "seconds": list(timings.values())})
    report.table(timing, "timings", "Seconds per experiment (all seeds)")


def _how_decided(n: int, k: int, seeds: str, tally: str) -> str:
    return (
        f"{n} findings of the paper, one per event, each judged on {k} independent "
        f"seed{'s' if k > 1 else ''} ({seeds}) by its written rule: {tally}. The "
        "rules were written down and committed before this run, on seeds not used while "
        "writing them. A finding whose quantity rests on one fitted object per seed (a GMM, a "
        "PCA, an empirical metric's training, a target built from the seed's own runs) is "
        "decided on the seeds' estimates, one per fit (rule 'seed level'); any other finding "
        "with an interval on the runs of all seeds pooled (paired where conditions share "
        "their runs' generators). 'Pooled interval' shows the estimate, its CI and the test, "
        "and 'per seed' each seed's own verdict on its own runs as a robustness check. A "
        "finding without an interval keeps the seeds' common verdict, **inconclusive** when "
        "they disagree. 'Effect over seeds' is the mean of the finding's effect size over the "
        f"seeds ± the half-width of its 95% t-interval ({k} seeds). Tables and figures above "
        "are the first seed's. Model-specific and oracle checks, findings that restate "
        "another's event, and our own checks are listed apart and are not in the tally."
    )


def tally_both_ways(verdicts: list[str]) -> str:
    """The tally in words, read strictly and leniently (rule 'tally'): the four counts; how
    many hold (strict: 'partly' does not hold) or hold at least partly (lenient); and the same
    among the decided findings (the inconclusive set aside)."""
    n = len(verdicts)
    c = {v: verdicts.count(v) for v in VERDICTS}
    decided = n - c["inconclusive"]
    words = f"{c['holds']} hold, {c['partly']} partly, {c['differs']} differ, "
    words += f"{c['inconclusive']} inconclusive"
    strict = f"strictly {c['holds']} of {n} hold"
    lenient = f"leniently (partly counted) {c['holds'] + c['partly']} of {n}"
    among = (
        f"among the {decided} decided, {c['holds']} hold and {c['holds'] + c['partly']} hold "
        f"at least partly, {c['differs']} differ"
    )
    return f"{words} — {strict}, {lenient}; {among}"


def _write_changed(report: Report, combined: list[Combined], s: ReplicateSettings) -> None:
    """Every verdict that moved from the previous report (issue #30's), and why."""
    changed = _changed(combined, s)
    report.heading("Verdicts that moved with issue #41", level=3)
    report.paragraph(
        f"{len(changed)} findings moved from the previous report (issue #30: seeds 1–3, runs "
        "pooled for every interval, no smallest effect of interest, asymmetric joins, every "
        "paper finding counted): verdicts that changed, and findings that left the tally. "
        "'Why' names the rule changes of issue #41 that apply to the finding (decided before "
        "this run) and the seeds' own verdicts; a finding whose rules did not change moved "
        "with the new seeds alone."
    )
    report.table(changed, "verdict_changes", "Every verdict that moved, and why")


def _changed(combined: list[Combined], s: ReplicateSettings) -> pd.DataFrame:
    """Findings whose verdict or place (counted / apart) differs from
    :data:`~.previous.BEFORE`, with the rule changes that apply to each."""
    from emogen.analysis.replication.previous import BEFORE, WHY

    rows = []
    for c in combined:
        f = c.finding
        if f.key not in BEFORE:
            continue
        number, old = BEFORE[f.key]
        now = c.verdict + (" (outside the tally)" if f.outside else "")
        if now == old:
            continue
        rows.append(
            {
                "finding (previous no.)": number,
                "section": f.section,
                "claim": f.claim,
                "before": old,
                "now": now,
                "why": "; ".join(_reasons(c, WHY.get(f.claim, ""), s)),
            }
        )
    columns = ["finding (previous no.)", "section", "claim", "before", "now", "why"]
    return pd.DataFrame(rows, columns=columns)


def _reasons(c: Combined, specific: str, s: ReplicateSettings) -> list[str]:
    f = c.finding
    out = [specific] if specific else []
    if f.fitted:
        out.append(f"seed level: the seeds' estimates, each its own {f.fitted}")
    if "SESOI" in c.interval:
        out.append("a smallest effect of interest (rule ci)")
    if len(f.evidence) > 1:
        out.append("parts joined symmetrically (rule join)")
    per_seed = ", ".join(f"{n} {v}" for v in VERDICTS if (n := c.seed_verdicts.count(v)))
    out.append(f"new seeds {s.seed_list[0]}–{s.seed_list[-1]} (per seed: {per_seed})")
    return out


def _rules_table() -> pd.DataFrame:
    from emogen.analysis.replication.verdicts import RULES

    return pd.DataFrame({"rule": list(RULES), "what it says": list(RULES.values())})


def _records(combined: list[Combined]) -> pd.DataFrame:
    """The findings for machines: the effect as numbers (mean over seeds, 95% CI half-width,
    what it measures) and each seed's verdict in its own column (``verdict_seed_<k>``)."""
    rows = []
    for c in combined:
        f = c.finding
        has = f.value is not None and bool(np.isfinite(c.mean))
        row: dict[str, object] = {
            "section": f.section,
            "paper_finding": f.claim,
            "paper": f.paper,
            "ours_first_seed": f.ours,
            "effect_mean": c.mean if has else None,
            "effect_ci_half_width": c.half_width if has and np.isfinite(c.half_width) else None,
            "effect_measure": f.value_label if has else None,
            "pooled_interval": c.interval or None,
            "rule": f.rule,
            "verdict": c.verdict,
            "decided_on": f"seeds' estimates ({f.fitted})" if f.fitted else "runs pooled",
            "outside_tally": f.outside or None,
            "n_seeds": len(c.seed_verdicts),
            "note": f.note,
        }
        row.update({f"verdict_seed_{k + 1}": v for k, v in enumerate(c.seed_verdicts)})
        rows.append(row)
    return pd.DataFrame(rows)


def _rows(combined: list[Combined], reason: bool = False) -> pd.DataFrame:
    return pd.DataFrame(
        [
            ({"why apart": c.finding.outside} if reason else {})
            | {
                "section": c.finding.section,
                "paper finding": c.finding.claim,
                "paper": c.finding.paper,
                "ours (first seed)": c.finding.ours,
                "effect over seeds": c.effect,
                "pooled interval": c.interval or "–",
                "rule": c.finding.rule,
                "per seed": " / ".join(c.seed_verdicts),
                "verdict": f"**{c.verdict}**",
                "note": c.finding.note,
            }
            for c in combined
        ]
    )
