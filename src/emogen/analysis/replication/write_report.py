"""The replication report's frame: the introduction, rendered face figures, and the closing
table of every finding with the run's timings."""

from __future__ import annotations

import platform
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis.replication.findings import VERDICTS, Finding
from emogen.analysis.replication.settings import ReplicateSettings
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
        "paper's numbers with a verdict: **holds**, **partly** (in part, or only qualitatively) "
        "or **differs**. The closing table lists them all."
    )
    report.bullets(
        [
            f"{s.runs} simulated runs per condition (the paper: 500), 10 generations, the paper's "
            "selection schedule (2, then 4 in generations 1–5, then 5), protocol initialisation "
            "with 3–8 active genes, a noiseless CD observer — unless a section says otherwise.",
            f"One seed for every condition ({s.seed}): conditions differ only by their settings.",
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
    findings: list[Finding],
    timings: dict[str, float],
    *,
    glance_at: int,
    seconds: float,
    version: str,
    settings: ReplicateSettings,
) -> None:
    """The findings table (and its tally at ``glance_at``), the run's versions and timings."""
    report.heading("Findings: the paper beside ours")
    counts = pd.Series([f.verdict for f in findings]).value_counts()
    words = {"holds": "hold", "partly": "partly", "differs": "differ"}
    tally = ", ".join(f"{counts.get(v, 0)} {words[v]}" for v in VERDICTS)
    report.paragraph(f"{len(findings)} findings: {tally}.")
    glance = (
        f"**At a glance:** {len(findings)} findings of the paper checked on our model: {tally}. "
        "The closing table lists every one with the paper's numbers beside ours."
    )
    report.insert_paragraph(glance_at, glance)
    table = pd.DataFrame(
        [
            {
                "section": f.section,
                "paper finding": f.claim,
                "paper": f.paper,
                "ours": f.ours,
                "verdict": f"**{f.verdict}**",
                "note": f.note,
            }
            for f in findings
        ]
    )
    report.table(table, "findings", "Every finding, with the paper's numbers and ours")
    timing = pd.DataFrame({"experiment": list(timings), "seconds": list(timings.values())})
    report.heading("Run", level=3)
    quick = " --quick" if settings.quick else ""
    report.paragraph(
        f"EmoGen {version}, Python {platform.python_version()}, {platform.machine()}; "
        f"{'quick' if settings.quick else 'full'} run in {seconds:.0f} s. Regenerate with "
        f"`emogen replicate{quick} --out DIR`."
    )
    report.table(timing, "timings", "Seconds per experiment")
