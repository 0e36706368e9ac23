"""Between-session reliability: does a participant make the same face on another day?

A retest study (``retest_of``: :mod:`emogen.study.retest`) has the same participants make the
same emotions again. For each emotion × identity, each participant's final faces of one
session are averaged (their repetitions), and the two sessions' faces are the participant's
two "repetitions" of the one-way random-effects model of :mod:`emogen.analysis.reliability`:
ICC = σ²_b / (σ²_b + σ²_w) on the genes, with its jackknife interval over participants (the
participant is the unit). Beside it, the within-session ICC of the first session (its
repetitions, where it had any): the two answer different questions — the within-session
figure is the stability of a face within minutes, the between-session one over days — and the
report says which is which.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis.people import People
from emogen.analysis.reliability import components, icc_interval
from emogen.analysis.results import Section
from emogen.errors import DataError

if TYPE_CHECKING:
    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.model import FaceModel

COLUMNS = (
    "emotion",
    "identity",
    "participants",
    "icc_between_sessions",
    "ci_low",
    "ci_high",
    "icc_within_session",
    "within_ci_low",
    "within_ci_high",
)


def _icc(x: np.ndarray, who: np.ndarray, level: float) -> tuple[float, float, float]:
    """ICC and its interval; NaN where fewer than 3 participants have 2 faces."""
    counts = pd.Series(who).value_counts()
    if (counts >= 2).sum() < 3:
        return float("nan"), float("nan"), float("nan")
    icc = components(x, who).icc
    low, high = icc_interval(x, who, confidence=level)
    return icc, low, high


def retest_table(first: People, second: People, *, level: float = 0.95) -> pd.DataFrame:
    """Per emotion × identity: the participants in both sessions, the between-session ICC of
    their mean final faces (genes) with its interval, and the first session's within-session
    ICC (NaN where it had no repetitions)."""
    if list(first.genes) != list(second.genes):
        raise DataError(
            "the two exports have different gene columns: a retest must run the same rig "
            f"({len(first.genes)} against {len(second.genes)} genes)"
        )
    genes = list(first.genes)
    keys = ["participant_id", "emotion", "identity"]
    one = first.faces.groupby(keys)[genes].mean()
    two = second.faces.groupby(keys)[genes].mean()
    both = one.index.intersection(two.index)
    if len(both) == 0:
        raise DataError(
            "no participant made the same emotion on the same identity in both exports: is the "
            "second the retest of the first (the same participant ids)?"
        )
    rows = []
    for (emotion, identity), cell in pd.DataFrame(index=both).groupby(level=[1, 2]):
        index = cell.index
        x = np.vstack([one.loc[index].to_numpy(), two.loc[index].to_numpy()])
        who = np.concatenate([index.get_level_values(0)] * 2).astype(str)
        between = _icc(x, who, level)
        rep = first.faces[
            (first.faces["emotion"] == emotion) & (first.faces["identity"] == identity)
        ]
        within = _icc(
            rep[genes].to_numpy(dtype=np.float64), rep["participant_id"].to_numpy(), level
        )
        rows.append((emotion, identity, len(index), *between, *within))
    return pd.DataFrame(rows, columns=list(COLUMNS))


def retest_text(table: pd.DataFrame, level: float = 0.95) -> str:
    """The report's paragraph: what is reported, and the figures."""
    lines = [
        "**Between-session reliability** (a retest on another day): per emotion × identity, "
        "each participant's mean final face (genes) in the first session and in the retest "
        "are their two measurements; ICC(1) = σ²_b / (σ²_b + σ²_w) with a "
        f"{level:.0%} jackknife interval over participants (the participant is the unit). "
        "Beside it, the **within-session** ICC of the first session's repetitions (NA where it "
        "had none): stability within minutes, not across days. This report's reliability is "
        "the between-session one.",
        "",
    ]
    for r in table.to_dict("records"):
        within = (
            "no repetitions within the session"
            if pd.isna(r["icc_within_session"])
            else f"within-session ICC {r['icc_within_session']:.2f} "
            f"[{r['within_ci_low']:.2f}, {r['within_ci_high']:.2f}]"
        )
        between = (
            "too few participants in both sessions"
            if pd.isna(r["icc_between_sessions"])
            else f"between-session ICC {r['icc_between_sessions']:.2f} "
            f"[{r['ci_low']:.2f}, {r['ci_high']:.2f}]"
        )
        lines.append(
            f"- {r['emotion']} on {r['identity']} (n = {r['participants']}): {between}; {within}"
        )
    return "\n".join(lines)


def retest_section(
    people: People, folder: Path, opts: AnalysisOptions, model: FaceModel | None
) -> Section:
    """``emogen analyse FIRST RETEST``: the between-session section, the retest export read
    with the same exclusion rule as the first (nothing where no retest export is given)."""
    report = Section(folder)
    if opts.retest is None:
        return report
    from emogen.analysis.exclusions import apply_exclusions
    from emogen.analysis.people import load_people
    from emogen.errors import EmoGenError

    report.heading("Between-session reliability (retest)")
    try:
        second = load_people(opts.retest)
        everyone = second.n_participants
        if opts.exclusions is not None and not second.faces.empty:
            second, _ = apply_exclusions(second, opts.exclusions)
        table = retest_table(people, second)
    except EmoGenError as exc:
        report.paragraph(f"No between-session reliability from {opts.retest}: {exc}.")
        return report
    report.paragraph(
        f"The retest export {opts.retest.name}: {second.n_participants} participants "
        f"analysed ({everyone - second.n_participants} excluded by the same rule).\n\n"
        f"{retest_text(table)}"
    )
    report.table(table, "retest", "Between-session ICC per emotion × identity (genes)")
    report.data["retest"] = {
        "reported": "between-session ICC(1) of the participants' mean final faces (genes)",
        "cells": table.to_dict("records"),
    }
    return report
