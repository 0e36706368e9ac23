"""Figures of the categorisation section: confusion matrices per face source, and the own-distance
model (the chosen share by distance to own and to reference faces; the shuffled control)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis import plots
from emogen.analysis.recognition import RANDOM_ROW

if TYPE_CHECKING:
    from emogen.analysis.categorisation_models import OwnDistance


def confusion_figure(table: pd.DataFrame, path: Path) -> Path:
    """Heat maps of row proportions (intended × label), one panel per source present, with the
    counts written in the cells; random faces (no intended emotion) as one row of label shares."""
    sources = [s for s in ("all", "own", "other", "file") if s in set(table["source"])]
    rand = table[table["source"] == "random"]
    labels = sorted(set(table["label"]))
    intended = sorted(set(table.loc[table["source"] != "random", "intended"]))
    panels = [*sources, *(["random"] if len(rand) else [])]
    fig = plots.new_figure(2.2 * len(panels) + 1.0, 0.45 * max(len(intended), 2) + 1.6)
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    image = None
    for ax, source in zip(axes, panels, strict=True):
        rows = [RANDOM_ROW] if source == "random" else intended
        part = table[table["source"] == source]
        share = np.zeros((len(rows), len(labels)))
        count = np.zeros((len(rows), len(labels)), dtype=np.int64)
        cells = zip(part["intended"], part["label"], part["proportion"], part["count"], strict=True)
        for intended, label, prop, n_cell in cells:
            if intended in rows:
                i, j = rows.index(str(intended)), labels.index(str(label))
                share[i, j], count[i, j] = float(prop), int(n_cell)
        image = ax.imshow(share, cmap="viridis", vmin=0.0, vmax=1.0, aspect="equal")
        for i in range(len(rows)):
            for j in range(len(labels)):
                ax.text(
                    j,
                    i,
                    str(count[i, j]),
                    ha="center",
                    va="center",
                    fontsize=6,
                    color="black" if share[i, j] > 0.6 else "white",
                )
        ax.set_xticks(range(len(labels)), labels, rotation=45, ha="right", fontsize=7)
        ax.set_yticks(range(len(rows)), rows if ax is axes[0] or source == "random" else [])
        n = int(part["count"].sum())
        ax.set_title(f"{source} faces (n = {n})", fontsize=8)
        ax.set_xlabel("label given", fontsize=7)
    axes[0].set_ylabel("intended emotion", fontsize=7)
    if image is not None:
        bar = fig.colorbar(image, ax=list(axes), shrink=0.8)
        bar.set_label("share of the row", fontsize=7)
    return plots.save_figure(fig, path)


def nearest_agreement(table: pd.DataFrame) -> pd.DataFrame:
    """Per participant: the share of answers whose label is the offered label with the nearest
    own mean face (``own``), and with the nearest reference mean face (``ref``)."""
    t = table.assign(
        own_rank=table.groupby(["participant_id", "answer"])["d_own"].rank(method="min"),
        ref_rank=table.groupby(["participant_id", "answer"])["d_ref"].rank(method="min"),
    )
    chosen = t[t["chosen"] == 1]
    return (
        chosen.assign(own=chosen["own_rank"] == 1, ref=chosen["ref_rank"] == 1)
        .groupby("participant_id")[["own", "ref"]]
        .mean()
        .reset_index()
    )


def own_distance_figure(res: OwnDistance, path: Path) -> Path:
    """A: per participant, how often the label given is the one whose mean face is nearest —
    among one's own faces against among the reference participant's (descriptive). B: the
    shuffled control's slopes with the own-face slope marked."""
    fig = plots.new_figure(7.2, 3.1)
    left, right = fig.subplots(1, 2)
    agree = nearest_agreement(res.table)
    left.plot([0, 1], [0, 1], color="0.6", lw=0.8, ls="--")
    left.scatter(agree["ref"], agree["own"], s=12, color=plots.colour(0), alpha=0.8)
    left.set_xlim(0, 1.02)
    left.set_ylim(0, 1.02)
    left.set_aspect("equal")
    left.set_xlabel("label = nearest of the reference's faces (share)")
    left.set_ylabel("label = nearest of one's own faces (share)")
    left.set_title(f"A. one dot per participant (n = {len(agree)})", fontsize=8)
    c = res.control
    if c["status"] == "ok":
        right.hist(c["control"], bins=20, color=plots.colour(4), label="shuffled (derangements)")
        right.axvline(c["slope_own"], color=plots.colour(5), lw=2, label="own faces")
    else:
        right.text(
            0.5,
            0.5,
            f"no estimate:\n{c['reason']}",
            ha="center",
            va="center",
            fontsize=7,
            wrap=True,
            transform=right.transAxes,
        )
    right.set_xlabel("conditional-logit slope on distance (per gene-ED unit)")
    right.set_ylabel("shuffles")
    right.set_title("B. shuffled-prototype control", fontsize=8)
    right.legend(fontsize=7, frameon=False)
    for ax in (left, right):
        ax.xaxis.label.set_fontsize(7)
        ax.yaxis.label.set_fontsize(7)
    return plots.save_figure(fig, path)
