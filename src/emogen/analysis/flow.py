"""The participants' flow through a study: a CONSORT-like table of how many arrived, consented,
started each block, finished, were excluded (and by which criterion), were analysed and came
back for a retest — per group where the analysis has groups of participants.

Every count is of participants (distinct ``participant_id``), read from the export's
``sessions`` and ``trials`` tables (all tasks) and the exclusion table of
:func:`emogen.analysis.exclusions.apply_exclusions`; a participant with several sessions (a
retest in the same database) counts once per stage reached in any of them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import pandas as pd

from emogen.analysis.results import Section
from emogen.analysis.study_export import StudyExport

if TYPE_CHECKING:
    from pathlib import Path

#: A participant without a row in the participant table, in the per-group columns.
NO_GROUP = "(not in the participant table)"

#: The exclusion criteria in the flow's words (the flags of the exclusion table).
CRITERIA = {
    "fast": "median response time below the floor",
    "one_tile": "generation-0 elite on one tile",
    "keeps_tile0": "elite kept on tile 0",
    "incomplete": "too few GA trials finished",
    "one_label": "one categorise answer throughout",
    "at_chance": "categorise accuracy at or below chance",
    "fast_labels": "categorise answers below the time floor",
}


def _ids(frame: pd.DataFrame, mask: Any = None) -> set[str]:
    rows = frame if mask is None else frame[mask]
    return set(rows["participant_id"].astype(str))


def flow_stages(
    sessions: pd.DataFrame,
    trials: pd.DataFrame,
    exclusions: pd.DataFrame | None,
    analysed: set[str],
) -> list[tuple[str, set[str]]]:
    """The stages in order, each with the participants who reached it."""
    stages = [("arrived (a session made)", _ids(sessions))]
    stages.append(("consented", _ids(sessions, sessions["consented_at"].notna())))
    started = trials[trials["status"].astype(str) != "pending"]
    blocks = trials[["block", "block_name"]].drop_duplicates("block").sort_values("block")
    for block, name in blocks.itertuples(index=False):
        label = f"started block {int(block) + 1} ({name})"
        stages.append((label, _ids(started, started["block"] == block)))
    stages.append(("finished the study", _ids(sessions, sessions["stage"].astype(str) == "done")))
    if exclusions is not None:
        out = exclusions[exclusions["excluded"].astype(bool)]
        stages.append(("excluded by the rule", _ids(out)))
        for flag, words in CRITERIA.items():
            if flag in out.columns:
                stages.append((f"excluded: {words}", _ids(out, out[flag].astype(bool))))
    stages.append(("analysed (finished faces, not excluded)", set(analysed)))
    if "retest_of_session_id" in sessions.columns:
        back = sessions["retest_of_session_id"].notna()
        stages.append(("retest sessions (matched to a first session)", _ids(sessions, back)))
    return stages


def participant_flow(
    sessions: pd.DataFrame,
    trials: pd.DataFrame,
    exclusions: pd.DataFrame | None,
    analysed: set[str],
    groups: pd.Series | None = None,
) -> pd.DataFrame:
    """One row per stage: ``stage``, ``participants`` (all) and, with ``groups`` (a group label
    per participant id), one column per group (``NO_GROUP`` for participants it lacks)."""
    stages = flow_stages(sessions, trials, exclusions, analysed)
    table = pd.DataFrame(
        {"stage": [s for s, _ in stages], "participants": [len(ids) for _, ids in stages]}
    )
    if groups is None:
        return table
    label = {str(k): str(v) for k, v in groups.items() if pd.notna(v)}
    names = sorted(set(label.values()))
    everyone = set().union(*(ids for _, ids in stages))
    if everyone - set(label):
        names.append(NO_GROUP)
    for name in names:
        table[name] = [sum(label.get(p, NO_GROUP) == name for p in ids) for _, ids in stages]
    return table


def flow_section(
    export: StudyExport,
    exclusions: pd.DataFrame | None,
    analysed: set[str],
    folder: Path,
    groups: pd.Series | None = None,
) -> Section:
    """The participant-flow table of ``export`` (its counts in ``analysis.json``'s ``flow``)."""
    report = Section(folder)
    sessions, trials = export.table("sessions"), export.table("trials")
    if sessions is None or trials is None or "block_name" not in trials.columns:
        report.paragraph("Participant flow: the export has no sessions or trials table.")
        return report
    table = participant_flow(sessions, trials, exclusions, analysed, groups)
    report.paragraph(
        "**Participant flow.** Participants (distinct ids) reaching each stage, read from the "
        "export's sessions and trials (a block is started when one of its trials is no longer "
        "pending; finished: the session's stage is done). A participant may meet several "
        "exclusion criteria, so the criterion lines can sum to more than the excluded."
        + (" Per group as the participant table assigns them." if groups is not None else "")
    )
    report.table(table, "participant_flow", "Participant flow (CONSORT-like).")
    report.data["flow"] = dict(zip(table["stage"], table["participants"], strict=True))
    return report
