"""``emogen analyse``'s analyses of people (study exports): the participant is the unit.

Read from the export as :class:`~emogen.analysis.people.People` (one row per final face), with
the participant table joined when given (``--participants``). The exclusion rule
(:mod:`emogen.analysis.exclusions`, stated in the report) is applied **once, before every
analysis**: :func:`prepare_people` returns the people kept and the rule's table, the quality
section reports that table, and ``emogen analyse`` reloads the GA data without the excluded
participants. Each section states its unit, model and assumptions, and says
in one line why when the design cannot support it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from emogen.analysis.categorisation import categorisation_section
from emogen.analysis.conditions import conditions_section
from emogen.analysis.exclusions import ExclusionRule, apply_exclusions
from emogen.analysis.fields_report import fields_section
from emogen.analysis.flow import flow_section
from emogen.analysis.genes_report import genes_section
from emogen.analysis.groups import groups_section
from emogen.analysis.identity import identity_section
from emogen.analysis.people import load_people, read_participant_table
from emogen.analysis.quality_report import quality_section
from emogen.analysis.reliability_report import reliability_section
from emogen.analysis.results import Section
from emogen.analysis.retest import retest_section
from emogen.analysis.study_export import StudyExport
from emogen.errors import ConfigError, EmoGenError

if TYPE_CHECKING:
    from collections.abc import Callable

    import pandas as pd

    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.analysis.data import Dataset
    from emogen.analysis.people import People
    from emogen.appearance.identities import Identity
    from emogen.model.face import FaceModel


@dataclass(frozen=True, eq=False)
class Prepared:
    """Everyone (for the quality section), the people kept, who was excluded, and why there
    are no people (``problem``) when the export cannot give them. ``exclusions``: the table of
    the rule's one application (:func:`apply_exclusions`: measures, flags, ``excluded``,
    ``reasons``; under ``--no-exclusions`` the default rule's flags, for information only,
    nobody excluded); None without faces."""

    everyone: People | None
    kept: People | None
    excluded: frozenset[str]
    problem: str = ""
    export: StudyExport | None = None  # its sessions and trials: the participant flow
    exclusions: pd.DataFrame | None = None


def people_for(export: StudyExport, opts: AnalysisOptions) -> People:
    """The export's people, the participant table joined (errors name what is wrong)."""
    people = load_people(export)
    if opts.participants is not None:
        people = people.with_participants(read_participant_table(opts.participants))
    return people


def prepare_people(source: Path | StudyExport, opts: AnalysisOptions) -> Prepared:
    """The study's people with the exclusion rule applied (none: ``opts.exclusions`` None);
    ``source``: the export, or its folder."""
    export = source if isinstance(source, StudyExport) else StudyExport(source)
    try:
        everyone = people_for(export, opts)
    except EmoGenError as exc:
        return Prepared(None, None, frozenset(), str(exc), export)
    if everyone.faces.empty:
        return Prepared(everyone, everyone, frozenset(), export=export)
    kept, table = apply_exclusions(everyone, opts.exclusions or ExclusionRule())
    if opts.exclusions is None:  # the default rule's flags are shown, not applied
        return Prepared(everyone, everyone, frozenset(), export=export, exclusions=table)
    out = frozenset(table.loc[table["excluded"], "participant_id"].astype(str))
    return Prepared(everyone, kept, out, export=export, exclusions=table)


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
    load_people(ds.export or ds.source).with_participants(frame)


def quality_first(prepared: Prepared, out: Path, opts: AnalysisOptions) -> list[Section]:
    """Quality and exclusions, and the participant flow: reported before the analyses they
    apply to (none where the export gives no people)."""
    everyone, kept, table = prepared.everyone, prepared.kept, prepared.exclusions
    if everyone is None or kept is None or table is None:  # no faces: no quality to report
        return []
    quality = quality_section(everyone, out, opts, rule=opts.exclusions, applied=(kept, table))
    sections = [quality]
    if prepared.export is not None:
        analysed = set(kept.faces["participant_id"].astype(str))
        rule_table = table if opts.exclusions is not None else None
        sections.append(flow_section(prepared.export, rule_table, analysed, out, _groups(opts)))
    if prepared.excluded:
        note = Section(out)
        note.paragraph(
            f"**{len(prepared.excluded)} participant(s) excluded by the rule above** "
            f"({', '.join(sorted(prepared.excluded))}): every section below is without them."
        )
        sections.append(note)
    return sections


def _groups(opts: AnalysisOptions) -> pd.Series | None:
    """Each participant's group from the participant table (None without one or its column)."""
    if opts.participants is None:
        return None
    frame = read_participant_table(opts.participants)
    if opts.group_column not in frame.columns:
        return None
    return frame.set_index(frame["participant_id"].astype(str))[opts.group_column]


def people_sections(
    prepared: Prepared,
    out: Path,
    opts: AnalysisOptions,
    model: FaceModel | None,
    step: Callable[[str], None],
) -> list[Section]:
    """The analyses of participants, each a section (``out``: the report's folder)."""
    people = prepared.kept
    if people is None:
        none = Section(out)
        none.heading("Analyses of participants")
        none.paragraph(f"No analyses of participants: {prepared.problem}")
        return [none]
    step("categorisation")
    sections = [categorisation_section(people, out, opts, model)]
    if people.faces.empty:
        none = Section(out)
        none.heading("Analyses of the faces participants made")
        none.paragraph(
            "None: no GA trial is finished (reliability, per-gene inference, conditions, "
            "perceptive fields, identity and group comparisons need final faces)."
        )
        return [*sections, none]
    sections.append(Section(out, data={"participants": people.n_participants}))
    for name, section in (
        ("reliability", reliability_section),
        ("per-gene inference", genes_section),
        ("conditions (emotion × identity)", conditions_section),
        ("perceptive fields", fields_section),
        ("identity effects", identity_section),
        ("between-session reliability", retest_section),
    ):
        step(name)
        sections.append(section(people, out, opts, model))
    step("groups of participants")
    sections.append(groups_section(people, out, opts, opts.group_column))
    return sections


def group_identities(prepared: Prepared | None) -> dict[str, Identity]:
    """The identity (shape and appearance) each GA group was made on, by group label
    (``emotion`` or ``emotion / identity``), to draw mean faces as participants saw them."""
    from emogen.analysis.field_maps import study_identities

    people = prepared.kept if prepared is not None else None
    if people is None or people.faces.empty:
        return {}
    idents = study_identities(people)
    several = len(people.identity_names) > 1
    pairs = people.faces[["emotion", "identity"]].drop_duplicates().itertuples(index=False)
    return {
        (f"{e} / {i}" if several else str(e)): idents[str(i)] for e, i in pairs if str(i) in idents
    }
