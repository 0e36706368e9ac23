"""``emogen analyse``'s analyses of people (study exports): the participant is the unit.

Read from the export as :class:`~emogen.analysis.people.People` (one row per final face), with
the participant table joined when given (``--participants``); each section states its unit,
model and assumptions, and says in one line why when the design cannot support it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from emogen.analysis.groups import groups_section
from emogen.analysis.people import load_people, read_participant_table
from emogen.analysis.reliability_report import reliability_section
from emogen.errors import ConfigError, EmoGenError

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.analysis.data import Dataset
    from emogen.analysis.people import People
    from emogen.analysis.report import Report
    from emogen.model.face import FaceModel


def people_for(source: Path, opts: AnalysisOptions) -> People:
    """The export's people, the participant table joined (errors name what is wrong)."""
    people = load_people(source)
    if opts.participants is not None:
        people = people.with_participants(read_participant_table(opts.participants))
    return people


def check_participants(ds: Dataset, table: Path, group_column: str) -> None:
    """A participant table that cannot be used, refused before any work: not a study export,
    unreadable, no participant_id, a participant missing, or no ``group_column``."""
    if ds.kind != "study":
        raise ConfigError("--participants needs a study export (a simulation has no participants)")
    frame = read_participant_table(table)
    if group_column not in frame.columns:
        raise ConfigError(
            f"participant table {table} has no column '{group_column}' (--group-column); it "
            f"has {', '.join(map(str, frame.columns))}"
        )
    load_people(ds.source).with_participants(frame)


def people_sections(
    source: Path,
    report: Report,
    summary: dict[str, Any],
    opts: AnalysisOptions,
    model: FaceModel | None,
    step: Callable[[str], None],
) -> None:
    try:
        people = people_for(source, opts)
    except EmoGenError as exc:
        report.heading("Analyses of participants")
        report.paragraph(f"No analyses of participants: {exc}")
        return
    summary["participants"] = people.n_participants
    if people.faces.empty:
        report.heading("Analyses of participants")
        report.paragraph(
            "No analyses of participants: no GA trial is finished yet (they need final faces)."
        )
        return
    step("reliability")
    reliability_section(people, report, summary, opts, model)
    step("groups of participants")
    groups_section(people, report, summary, opts, opts.group_column)
