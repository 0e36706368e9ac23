"""The quality and exclusions section of the report of people."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.exclusions import ExclusionRule
from emogen.analysis.people import People
from emogen.analysis.quality import participant_quality, position_bias, selection_positions
from emogen.analysis.results import Section

if TYPE_CHECKING:
    from pathlib import Path

#: Monte Carlo draws of the position-bias null.
DRAWS = 2000


def quality_section(
    people: People,
    folder: Path,
    opts: AnalysisOptions,
    *,
    rule: ExclusionRule | None,
    applied: tuple[People, pd.DataFrame],
) -> Section:
    """Quality per participant and session, the position-bias test and the exclusion rule
    applied (``rule``; None: none applied, ``--no-exclusions``, and the default rule's flags
    shown for information only); ``people`` are **all** participants, before exclusions;
    ``applied``: the people kept and the exclusion table of the rule's one application
    (:func:`~emogen.analysis.analyse_people.prepare_people`: the default rule's flags when
    ``rule`` is None), reported as they are, never computed again. The section: headline
    numbers in ``analysis.json``'s ``quality``, the position-bias test a typed result."""
    report = Section(folder)
    report.heading("Data quality and exclusions")
    quality = participant_quality(people)
    report.paragraph(
        "Per participant and session: `session_minutes` (consent → completion), GA trials planned "
        "and finished, the median trial duration (first face shown → trial end), the median "
        "selection response time (`client_response_ms`; the server time where the browser sent "
        "none; none for simulated participants, whose server times are machine times) and the "
        "share of elites on tile 0 — from generation 1 on tile 0 holds the carried elite, so "
        "this is descriptive, not a bias."
    )
    report.table(quality, "quality_sessions", "Quality per participant and session.")
    out: dict[str, Any] = {"participants": people.n_participants}
    _position(people, report, opts, out)
    kept, table = applied
    if rule is None:
        _not_applied(table, report, out)
    else:
        _applied(rule, kept, table, report, out)
    report.data["quality"] = out
    return report


def _applied(
    rule: ExclusionRule, kept: People, table: pd.DataFrame, report: Section, out: dict
) -> None:
    excluded = table[table["excluded"]]
    report.paragraph(
        "**Exclusion rule** (stated before the analysis; a participant is excluded when any "
        "criterion holds; measures over all their sessions): " + "; ".join(rule.describe()) + ". "
        "Every other section analyses the participants kept."
    )
    if excluded.empty:
        report.paragraph(f"No participant was excluded ({len(table)} kept).")
    else:
        report.paragraph(
            f"{len(excluded)} of {len(table)} participants excluded; {kept.n_participants} kept."
        )
        report.table(
            excluded[["participant_id", "reasons"]].reset_index(drop=True),
            None,
            "Excluded participants and why.",
        )
    report.table(table, "quality_exclusions", "Exclusion measures and flags, every participant.")
    out["excluded"] = int(table["excluded"].sum())
    out["excluded_ids"] = sorted(excluded["participant_id"].astype(str))


def _not_applied(table: pd.DataFrame, report: Section, out: dict) -> None:
    """``--no-exclusions``: nobody excluded; the default rule's flags for information."""
    flagged = sorted(table.loc[table["excluded"], "participant_id"].astype(str))
    report.paragraph(
        "**No exclusion rule applied** (`--no-exclusions`): every participant is analysed. For "
        "information only, the default rule (" + "; ".join(ExclusionRule().describe()) + ") "
        f"would exclude {len(flagged)} of {len(table)}"
        + (f" ({', '.join(flagged)})." if flagged else ".")
    )
    report.table(
        table,
        "quality_exclusions",
        "Exclusion measures and the default rule's flags (not applied), every participant.",
    )
    out["excluded"] = 0
    out["excluded_ids"] = []
    out["default_rule_would_exclude"] = flagged


def _position(people: People, report: Section, opts: AnalysisOptions, out: dict) -> None:
    sel = selection_positions(people)
    if sel is None or sel["position"].isna().all():
        report.paragraph(
            "Position bias: the export has no selections table with tile positions (a simulated "
            "study without the study server), so it cannot be tested."
        )
        return
    if not (sel["generation"] == 0).any():
        report.paragraph("Position bias: no generation-0 selections to test.")
        return
    rng = np.random.default_rng(opts.seed)
    n_tiles = int(sel["n_tiles"].iloc[0])
    table, overall = position_bias(sel, n_tiles, draws=DRAWS, rng=rng)
    flagged = int((table["p_mc"] < opts.alpha).sum())
    report.paragraph(
        "**Position bias.** Unit: the participant. Only generation-0 picks are tested (the first "
        "population is shuffled, so a participant who chooses by content picks every tile "
        "equally often; later tiles hold fixed GA operators). Test: the chi-square statistic of "
        f"the participant's picks per tile against uniform over {n_tiles} tiles, its p-value by "
        "Monte Carlo under random picks without replacement within a generation "
        f"({DRAWS} draws, seed {opts.seed}); overall: the sum of the participants' statistics "
        "against the sum of independent nulls. Assumes generations independent under H0. "
        f"Overall p = {overall['p_mc']:.3g}; {flagged} of {len(table)} participants have p < "
        f"{opts.alpha:g} (about {opts.alpha * len(table):.1f} expected by chance: a significant "
        "participant is not by itself careless)."
    )
    report.table(
        table,
        "quality_position_bias",
        "Generation-0 picks per participant: the most-picked tile and the position-bias test.",
    )
    test = "Monte Carlo chi-square sum"
    out["position_bias"] = record = {
        "test": test,
        "chi2_sum": overall["chi2_sum"],
        "p": overall["p_mc"],
        "draws": DRAWS,
        "n_participants": len(table),
        "flagged": flagged,
    }
    report.add_test(
        "quality.position_bias",
        record,
        test=test,
        p=overall["p_mc"],
        statistic=overall["chi2_sum"],
        n=len(table),
    )
