"""``emogen analyse``'s reliability section: test–retest reliability of each emotion's faces per
identity, in three spaces (:mod:`emogen.analysis.reliability`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.analysis import plots
from emogen.analysis.reliability import (
    SPACE_UNITS,
    SPACES,
    components,
    distances,
    features,
    icc_interval,
    split_half,
)
from emogen.analysis.results import Section
from emogen.errors import DataError

if TYPE_CHECKING:
    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.analysis.people import People
    from emogen.model.face import FaceModel

#: Fewer participants: no interval (the jackknife's t approximation is untested below 10).
MIN_FOR_INTERVAL = 10

COLUMNS = [
    "emotion",
    "identity",
    "space",
    "unit",
    "participants",
    "faces",
    "icc",
    "icc_low",
    "icc_high",
    "within_variance",
    "between_variance",
    "within_distance",
    "between_distance",
    "split_half_r",
    "spearman_brown",
    "self_identification",
    "chance",
    "p_identification",
]


def reliability_table(
    people: People, model: FaceModel | None, *, rng: np.random.Generator
) -> pd.DataFrame:
    """One row per emotion × identity × space with ≥ 2 participants who made it twice or more:
    ICC with its 95% jackknife interval over participants, variance components, mean within-
    and between-person distances (over participants) and the split-half statistics."""
    spaces = [s for s in SPACES if s != "vertex_rms" or model is not None]
    points = {s: features(people, s, model) for s in spaces}
    rows = []
    f = people.faces
    for (emotion, identity), cell in f.groupby(["emotion", "identity"], sort=True):
        repeated = cell.groupby("participant_id")["trial"].transform("size") >= 2
        if cell.loc[repeated, "participant_id"].nunique() < 2:
            continue
        idx = cell.index.to_numpy()
        who = cell["participant_id"].to_numpy()
        for space in spaces:
            x = points[space][idx]
            comp = components(x, who)
            lo, hi = (
                icc_interval(x, who) if comp.participants >= MIN_FOR_INTERVAL else (np.nan, np.nan)
            )
            dist = distances(x, who, space)
            half = split_half(x, who, cell["repetition"].to_numpy(), rng=rng)
            rows.append(
                {
                    "emotion": emotion,
                    "identity": identity,
                    "space": space,
                    "unit": SPACE_UNITS[space],
                    "participants": comp.participants,
                    "faces": comp.faces,
                    "icc": comp.icc,
                    "icc_low": lo,
                    "icc_high": hi,
                    "within_variance": comp.within,
                    "between_variance": comp.between,
                    "within_distance": float(dist["within"].mean()),
                    "between_distance": float(dist["between"].mean()),
                    "split_half_r": half.get("r_half", np.nan),
                    "spearman_brown": half.get("spearman_brown", np.nan),
                    "self_identification": half.get("self_identification", np.nan),
                    "chance": half.get("chance", np.nan),
                    "p_identification": half.get("p_identification", np.nan),
                }
            )
    return pd.DataFrame(rows, columns=COLUMNS)


def reliability_section(
    people: People, folder: Path, opts: AnalysisOptions, model: FaceModel | None
) -> Section:
    report = Section(folder)
    report.heading("Test–retest reliability")
    reps = people.faces.groupby(["participant_id", "emotion", "identity"]).size()
    if reps.empty or reps.max() < 2:
        report.paragraph(
            "No reliability: every participant made each emotion on each identity once "
            "(repetitions = 1); a test–retest analysis needs repeated trials of an emotion."
        )
        return report
    rng = np.random.default_rng(np.random.SeedSequence(opts.seed, spawn_key=(0x2E1,)))
    try:
        table = reliability_table(people, model, rng=rng)
    except DataError as exc:
        report.paragraph(f"No reliability: {exc}.")
        return report
    if table.empty:
        report.paragraph(
            "No reliability: fewer than 2 participants made any emotion twice on one identity."
        )
        return report
    report.paragraph(_method(opts, model))
    shown = table[
        [
            "emotion",
            "identity",
            "space",
            "participants",
            "icc",
            "icc_low",
            "icc_high",
            "within_distance",
            "between_distance",
            "spearman_brown",
            "self_identification",
            "chance",
        ]
    ]
    report.table(
        shown, "reliability", "Test–retest reliability per emotion, identity and space", data=table
    )
    report.figure(
        _forest(table, report.figures / "reliability_icc.png"),
        "ICC (share of the faces' variance that is the person) with 95% jackknife intervals "
        "over participants, per emotion × identity and space.",
    )
    ed = table[table["space"] == "ed"]
    report.data["reliability"] = {
        f"{r.emotion} / {r.identity}": {
            "icc": r.icc,
            "ci": [r.icc_low, r.icc_high],
            "participants": r.participants,
        }
        for r in ed.itertuples()
    }
    report.paragraph(_floor_text(table))
    return report


def _method(opts: AnalysisOptions, model: FaceModel | None) -> str:
    return (
        "Unit: the participant. For each emotion on each identity, the faces of participants "
        "who made it at least twice: ICC = σ²_b / (σ²_b + σ²_w), the one-way random-effects "
        "ICC(1) summed over the space's dimensions (= 1 − E d²within / E d²between), ANOVA "
        "estimates; 95% jackknife-t intervals over participants (leave one participant out; "
        f"none with fewer than {MIN_FOR_INTERVAL} participants). Split-half permutations: seed "
        f"{opts.seed}. Spaces: ED (genes), CD (unit-length "
        "corrected weights: ‖u − v‖² = 2·CD)"
        + (
            ", vertex RMS (cm, shapes and correctives blended linearly)"
            if model
            else "; vertex RMS needs the face model (not given)"
        )
        + ". Within/between distance: mean distance between a participant's own faces, and from "
        "them to other participants' faces, averaged over participants. Split-half: odd vs even "
        "repetitions' mean faces, vector correlation Spearman–Brown corrected; "
        "self-identification = share of participants whose halves are mutually nearest "
        "(chance 1/n). Assumptions: repetitions exchangeable (no learning across them), "
        "participants independent. A negative ICC estimate means no detectable person effect."
    )


def _floor_text(table: pd.DataFrame) -> str:
    """The empirical noise floor: within-person variation, beside the simulated GA noise."""
    cd = table[table["space"] == "cd"]
    if cd.empty:
        return ""
    floor = cd["within_distance"]
    return (
        "Empirical noise floor: the same participant's repeated faces lie a mean CD of "
        f"{floor.min():.3f}–{floor.max():.3f} apart (over the emotion × identity cells): GA "
        "noise plus the participant's own inconsistency, measured rather than simulated. The "
        "GA-noise section's simulated noise assumes one fixed target per participant; where "
        "the within-person distance exceeds it, participants' targets drift between trials."
    )


def _forest(table: pd.DataFrame, path: Any) -> Any:
    spaces = list(dict.fromkeys(table["space"]))
    cells = list(dict.fromkeys(table["emotion"] + " / " + table["identity"]))
    fig = plots.new_figure(2.4 * len(spaces) + 1.6, 0.28 * len(cells) + 1.2)
    axes = fig.subplots(1, len(spaces), sharey=True, squeeze=False)[0]
    for ax, space in zip(axes, spaces, strict=True):
        t = table[table["space"] == space]
        y = np.array([cells.index(c) for c in t["emotion"] + " / " + t["identity"]])
        ax.errorbar(
            t["icc"],
            y,
            xerr=[t["icc"] - t["icc_low"], t["icc_high"] - t["icc"]],
            fmt="o",
            color=plots.colour(0),
            ms=3,
            capsize=2,
            lw=1,
        )
        ax.axvline(0, color="0.6", lw=0.8, ls="--")
        ax.set_xlim(min(-0.1, float(t["icc_low"].min()) - 0.05), 1.0)
        ax.set_title(space, fontsize=8)
        ax.set_xlabel("ICC", fontsize=8)
    axes[0].set_yticks(range(len(cells)), cells, fontsize=7)
    axes[0].invert_yaxis()
    return plots.save_figure(fig, path)
