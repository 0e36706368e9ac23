"""``emogen analyse``'s sections that tasks write themselves (a task's optional
``analysis_section(tools)``, :mod:`emogen.tasks.protocol`).

Tasks sit below the analysis in the package's layers, so a task's section does not import it:
it is handed :class:`TaskTools` — the export's tables (the analysis's one loaded export), its
own :class:`~emogen.analysis.results.Section` of the report (``tools.report``), new figures
saved in the report's formats, faces drawn as participants saw them — and returns that section
filled (None: nothing to report): its content, its entries of ``analysis.json`` under the
task's name (``report.data``) and its tests as typed results
(:meth:`~emogen.analysis.results.Section.add_test`), in the multiplicity plan like every other
test.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.analysis import plots
from emogen.analysis.results import Section
from emogen.analysis.study_export import StudyExport
from emogen.tasks.registry import TASKS

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.appearance.identities import Identity
    from emogen.model.face import FaceModel


@dataclass(frozen=True)
class TaskTools:
    """What a task's analysis section works with; ``report``: the task's own section (fill
    and return it)."""

    export: StudyExport
    report: Section
    opts: AnalysisOptions
    model: FaceModel | None

    def table(self, name: str) -> pd.DataFrame | None:
        """The study export's table ``name`` (None where the export has none)."""
        return self.export.table(name)

    def new_figure(self, width: float, height: float) -> Figure:
        return plots.new_figure(width, height)

    def style(self, i: int) -> dict[str, Any]:
        """The line style of the i-th series (the report's colours and markers)."""
        return {"color": plots.colour(i), "marker": plots.marker(i)}

    def legend(self, ax: Any, n_entries: int) -> None:
        plots.legend_outside(ax, n_entries)

    def save_figure(self, fig: Figure, name: str, caption: str) -> Path:
        """The figure saved in the report's formats and shown in the report."""
        path = plots.save_figure(fig, self.report.figures / name)
        self.report.figure(path, caption)
        return path

    def identity(self, name: str) -> Identity:
        """The identity ``name`` as participants saw it: the study's own (the export's
        ``identities`` table), else the preset of that name (ConfigError: neither)."""
        from emogen.appearance.identities import resolve_identity
        from emogen.study.export import identities_from_table

        table = self.table("identities")
        known = (
            {} if table is None else {n: i for (_, n), i in identities_from_table(table).items()}
        )
        return resolve_identity(name, known)

    def face_sheet(
        self,
        genes: np.ndarray,
        labels: Sequence[str],
        identities: Sequence[str],
        name: str,
        caption: str,
    ) -> str | None:
        """Faces given by genes drawn on their identities, as participants saw them (shape
        weights; the study's own identities from the export's ``identities`` table); None when
        drawn, else why not (no model, ``--no-render``, an unknown identity)."""
        if self.model is None or not self.opts.render:
            return "no face model, or --no-render"
        from emogen.analysis.face_sheets import face_sheet
        from emogen.errors import EmoGenError

        rig = self.model.rig
        eye = genes.shape[1] == len(rig.gene_names(True))
        try:
            idents = [self.identity(i) for i in identities]
            path = face_sheet(
                self.model,
                rig.expand(genes, eye),
                list(labels),
                self.report.figures / name,
                size=self.opts.render_size,
                columns=min(4, len(labels)),
                identities=idents,
            )
        except EmoGenError as exc:
            return str(exc)
        self.report.figure(path, caption)
        return None


def task_sections(
    export: StudyExport,
    out: Path,
    opts: AnalysisOptions,
    model: FaceModel | None,
    step: Callable[[str], None],
) -> list[Section]:
    """Every registered task's own section, where it has one and has something to report
    (``out``: the report's folder)."""
    sections = []
    for task in TASKS.values():
        analysis = getattr(task, "analysis_section", None)
        if analysis is not None:
            step(f"{task.name} blocks")
            section = analysis(TaskTools(export, Section(out), opts, model))
            if section is not None and not isinstance(section, Section):
                raise TypeError(
                    f"task {task.name!r}: analysis_section returned {type(section).__name__}, "
                    "not its section (tools.report) or None"
                )
            if section is not None:
                sections.append(section)
    return sections
