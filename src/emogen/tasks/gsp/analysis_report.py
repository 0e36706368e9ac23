"""``emogen analyse``'s section on a study's GSP blocks (:mod:`emogen.tasks.gsp.analysis`):
per concept the chain aggregate with bootstrap intervals over chains, the convergence curves,
the aggregates drawn as participants saw them, how far apart the concepts' aggregates are, and
each aggregate against the GA's mean final face of the same emotion."""

from __future__ import annotations

from itertools import combinations
from typing import Any

import numpy as np
import pandas as pd

from emogen.tasks.gsp.analysis import (
    Chains,
    aggregate,
    chains_of,
    compare,
    convergence,
    participant_means,
)


def gsp_section(tools: Any) -> Any:
    """The section, ``tools.report`` filled (None where the export has no GSP answers);
    ``tools``: :class:`emogen.analysis.task_sections.TaskTools`. It estimates with intervals
    and tests nothing, so it adds no result to the multiplicity plan."""
    report, opts = tools.report, tools.opts
    iterations = tools.table("gsp_iterations")
    if iterations is None or iterations.empty:
        return None
    report.heading("Gibbs sampling with people (GSP)")
    concepts = chains_of(iterations)
    if not concepts:
        report.paragraph("No GSP analysis: no chain has a complete node yet.")
        report.data["gsp"] = {"n_answers": len(iterations), "note": "no complete node"}
        return report
    rng = np.random.default_rng(opts.seed)
    report.paragraph(
        f"{len(iterations)} slider answers of {iterations['participant_id'].nunique()} "
        f"participants in {sum(len(c.chain_ids) for c in concepts)} chains. The unit is the "
        "chain: a concept's aggregate is the mean of its chains' last faces (Harrison et al. "
        f"2020), with {int(100 * (1 - opts.alpha))}% percentile bootstrap intervals over "
        "chains; distances are in gene space (ED; CD, eq. 12, on genes)."
    )
    aggregates = pd.concat([aggregate(c, rng, opts.alpha) for c in concepts], ignore_index=True)
    curves = pd.concat([convergence(c) for c in concepts], ignore_index=True)
    out: dict[str, Any] = {"n_answers": len(iterations), "concepts": {}}
    for c in concepts:
        curve = curves[(curves["block_name"] == c.block_name) & (curves["emotion"] == c.emotion)]
        first, last = curve.iloc[0], curve.iloc[-1]
        out["concepts"][c.emotion] = {
            "n_chains": len(c.chain_ids),
            "nodes": int(last["iteration"]),
            "between_chains_first": float(first["between_chains"]),
            "between_chains_last": float(last["between_chains"]),
        }
    _convergence(curves, tools)
    cells = aggregates.assign(
        cell=[
            f"{m:.2f} [{lo:.2f}, {hi:.2f}]"
            for m, lo, hi in aggregates[["mean", "ci_low", "ci_high"]].itertuples(index=False)
        ]
    )
    moved = aggregates.groupby("gene")["ci_high"].max() > 0  # genes no chain ever moved: left out
    wide = cells.pivot_table(index="gene", columns="emotion", values="cell", aggfunc="first")
    report.table(
        wide.loc[[g for g in wide.index if moved[g]]],
        name="gsp_aggregates",
        caption="Chain aggregates: per gene and concept, the mean of the chains' last faces "
        "[bootstrap interval over chains] (every gene: the CSV).",
        index=True,
        data=aggregates,
    )
    _draw(concepts, tools)
    out["between_concepts"] = _between(concepts, rng, opts.alpha, report)
    out["versus_ga"] = _versus_ga(concepts, tools.table("final_faces"), rng, opts.alpha, report)
    report.data["gsp"] = out
    return report


def _convergence(curves: pd.DataFrame, tools: Any) -> None:
    fig = tools.new_figure(7.0, 3.0)
    ax_between, ax_target = fig.subplots(1, 2)
    for i, ((block, emotion), rows) in enumerate(curves.groupby(["block_name", "emotion"])):
        label = str(emotion) if curves["block_name"].nunique() == 1 else f"{block}: {emotion}"
        style = {**tools.style(i), "ms": 3, "label": label}
        ax_between.plot(rows["iteration"], rows["between_chains"], "-", **style)
        ax_target.plot(rows["iteration"], rows["to_aggregate"], "-", **style)
    ax_between.set_ylabel("mean ED between chains")
    ax_target.set_ylabel("mean ED to the final aggregate")
    for ax in (ax_between, ax_target):
        ax.set_xlabel("chain node (complete)")
        ax.grid(alpha=0.3)
    tools.legend(ax_target, curves["emotion"].nunique())
    tools.save_figure(
        fig,
        "gsp_convergence.png",
        "GSP convergence: chains of a concept come together node by node.",
    )
    report = tools.report
    first = curves.groupby(["block_name", "emotion"]).head(1)
    last = curves.groupby(["block_name", "emotion"]).tail(1)
    shown = first.merge(last, on=["block_name", "emotion"], suffixes=("_first", "_last"))
    report.table(
        shown[
            [
                "block_name",
                "emotion",
                "between_chains_first",
                "between_chains_last",
                "iteration_last",
                "n_chains_last",
            ]
        ].round(4),
        name="gsp_convergence",
        caption="Mean ED between a concept's chains at their starts and at their last node "
        "(every node: the CSV).",
        data=curves,
    )


def _draw(concepts: list[Chains], tools: Any) -> None:
    """The aggregates drawn on the identity most of their chains showed."""
    genes = np.stack([c.finals.mean(axis=0) for c in concepts])
    idents = [max(set(c.identities), key=c.identities.count) for c in concepts]
    why = tools.face_sheet(
        genes,
        [c.emotion for c in concepts],
        idents,
        "gsp_aggregates.png",
        "GSP chain aggregates, drawn on the identity their chains showed (shape weights).",
    )
    if why is not None:
        tools.report.paragraph(f"The aggregates are not drawn: {why}.")


def _between(concepts: list[Chains], rng: Any, alpha: float, report: Any) -> list[dict[str, Any]]:
    rows = []
    for a, b in combinations(concepts, 2):
        if a.block_name == b.block_name:
            rows.append(
                {
                    "block_name": a.block_name,
                    "emotion_a": a.emotion,
                    "emotion_b": b.emotion,
                    **compare(a.finals, b.finals, rng, alpha),
                }
            )
    if rows:
        report.table(
            pd.DataFrame(rows).round(4),
            name="gsp_between_concepts",
            caption="How far apart the concepts' aggregates are (bootstrap over chains).",
        )
    return rows


def _versus_ga(
    concepts: list[Chains], finals: pd.DataFrame | None, rng: Any, alpha: float, report: Any
) -> list[dict[str, Any]]:
    rows = []
    for c in concepts:
        ga = participant_means(finals, c.emotion, c.genes) if finals is not None else None
        if ga is None or len(ga) < 2:
            continue
        rows.append(
            {
                "block_name": c.block_name,
                "emotion": c.emotion,
                "n_chains": len(c.chain_ids),
                "n_participants": len(ga),
                **compare(c.finals, ga, rng, alpha),
            }
        )
    if rows:
        report.table(
            pd.DataFrame(rows).round(4),
            name="gsp_versus_ga",
            caption="Each GSP aggregate against the GA's mean final face of the same emotion "
            "(chains and participants resampled).",
        )
    else:
        report.paragraph(
            "No comparison with the GA: no emotion has final GA faces of two participants or more."
        )
    return rows
