"""``emogen analyse``: the analysis of a study export or simulation output, as a report.

Sections (each skipped, with a note saying why, when the data cannot support it):

1. the data: groups, samples, participants, generations;
2. per-generation error distributions (CD of each generation's elite to the target, or to the
   group's mean final face when the target is latent) and the KL divergence between
   consecutive generations (density estimate: :mod:`emogen.analysis.distributions`);
3. initial target bias and repeatability bins of the final faces (Table III);
4. PCA + 3-cluster (one per group) GMM separability with cluster-to-group correspondence and
   the confusion table (Table I, Fig. 8);
5. GA noise and whether each group's spread exceeds it (:mod:`emogen.analysis.noise`): the
   noise is simulated on the model toward each group's mean final face with the data's GA
   settings (generations, population, selections per generation);
6. prototypes: each participant's mean final face per group, group means, renders and
   heatmaps (the mean face against the target, or against the neutral face);
7. ratings (studies);
8. the analyses of participants (studies; :mod:`emogen.analysis.analyse_people`): quality and
   the exclusion rule first, then categorisation (confusion matrices, unbiased hit rates,
   accuracy by source, the own-distance model), reliability, per-gene inference, conditions,
   perceptive fields, identity effects and groups of participants.

Each section is a :class:`~emogen.analysis.results.Section` (content, its entries of
``analysis.json``, its tests as typed results); one renderer
(:func:`~emogen.analysis.results.write_analysis`) writes everything to ``OUT``: ``index.html``
and ``README.md``, ``tables/*.csv`` and ``analysis.json`` (the headline numbers), with the
figures the sections saved under ``figures/``. A study's export is read once
(:class:`~emogen.analysis.study_export.StudyExport`) and handed to every section.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen import columns as tidy
from emogen.analysis import plots
from emogen.analysis.analyse_faces import prototypes_section, separability_section
from emogen.analysis.analyse_noise import noise_section
from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.analyse_people import (
    group_identities,
    people_sections,
    prepare_people,
    quality_first,
)
from emogen.analysis.data import Dataset, load_dataset
from emogen.analysis.distributions import generation_summary, kl_per_generation
from emogen.analysis.methods import methods_record, methods_text
from emogen.analysis.plan import mark_roles, plan_section
from emogen.analysis.repeatability import BIN_LABELS, repeatability_bins
from emogen.analysis.results import Result, Section, check_registered, write_analysis
from emogen.analysis.task_sections import task_sections

if TYPE_CHECKING:
    from emogen.appearance.identities import Identity
    from emogen.model.face import FaceModel

__all__ = ["AnalysisOptions", "AnalysisResult", "analyse"]


@dataclass
class AnalysisResult:
    out: Path
    html: Path
    markdown: Path
    summary: dict[str, Any] = field(default_factory=dict)  # analysis.json, as written
    results: list[Result] = field(default_factory=list)  # every test, its role set


def analyse(
    data: Path | Dataset,
    out: Path,
    *,
    model: FaceModel | None = None,
    options: AnalysisOptions | None = None,
    progress: Callable[[str], None] | None = None,
) -> AnalysisResult:
    """Analyse ``data`` (a folder or a loaded :class:`Dataset`) into a report in ``out``.

    progress : called with each section's name as it begins (the CLI shows it on a terminal).
    """
    opts = options or AnalysisOptions()
    step = progress or (lambda _name: None)
    ds = data if isinstance(data, Dataset) else load_dataset(Path(data))
    export = ds.export  # a study's export, each table read once, for every section
    prepared = prepare_people(export, opts) if export is not None else None
    if export is not None and prepared is not None and prepared.excluded:
        ds = load_dataset(export, exclude=prepared.excluded)  # every analysis without them
    out = Path(out)
    study = export.table("study") if export is not None else None
    methods = methods_record(ds, opts, model, study)
    head = Section(out, data={"source": str(ds.source), "kind": ds.kind})
    head.data |= {"groups": list(ds.groups), "methods": methods}
    head.paragraph(methods_text(methods))
    step("overview and error distributions")
    sections = [head, _overview(ds, out)]
    if prepared is not None:
        step("quality and exclusions")
        sections += quality_first(prepared, out, opts)
    if ds.groups:
        identities = group_identities(prepared) if model is not None and opts.render else {}
        sections += _ga_sections(ds, out, opts, model, step, identities)
    else:
        none = Section(out)
        none.heading("The GA's faces")
        none.paragraph(
            "None: the export has no GA trial (error distributions, repeatability, "
            "separability, GA noise and prototypes need them)."
        )
        sections.append(none)
    sections.append(_ratings(ds, out))
    if export is not None and prepared is not None:
        sections += people_sections(prepared, out, opts, model, step)
        sections += task_sections(export, out, opts, model, step)
    results = mark_roles(check_registered(sections), opts.primary)
    sections.append(plan_section(results, opts.primary, out))
    step("writing the report")
    if ds.has_weights:
        sections[-1].csv(ds.elites.rename(columns={c: f"w_{c}" for c in ds.columns}), "elites")
    title = f"EmoGen analysis: {ds.source.name}"
    html_path, md_path, json_path = write_analysis(title, out, sections, {})
    summary = json.loads(json_path.read_text())
    return AnalysisResult(out, html_path, md_path, summary, results)


def _ga_sections(
    ds: Dataset,
    out: Path,
    opts: AnalysisOptions,
    model: FaceModel | None,
    step: Callable[[str], None],
    identities: dict[str, Identity],
) -> list[Section]:
    """The sections on the GA's faces: errors, repeatability, separability, noise, prototypes."""
    sections = [_errors(ds, out)]
    step("repeatability")
    sections.append(_repeatability(ds, out))
    step("separability (PCA + GMM)")
    sections.append(separability_section(ds, out, opts))
    step(f"GA noise ({opts.noise_runs} simulated runs per group)")
    sections.append(noise_section(ds, out, opts, model))
    step("prototypes and renders")
    sections.append(prototypes_section(ds, out, opts, model, identities))
    return sections


# ---- sections ------------------------------------------------------------------------------
def _overview(ds: Dataset, out: Path) -> Section:
    sec = Section(out)
    sec.paragraph(
        f"Source: `{ds.source}` ({ds.kind}). Generations 0–{ds.generations}; errors are the "
        f"{ds.error_kind}. Tables are also CSV files under `tables/` (`elites.csv`: one row per "
        "elite, with its weights)."
    )
    rows = []
    for g in ds.groups:
        e = ds.elites[ds.elites["group"] == g]
        rows.append(
            {
                "group": g,
                "samples": e["sample"].nunique(),
                "complete": e.loc[e["complete"], "sample"].nunique(),
                "participants": e["participant"].nunique() if ds.kind == "study" else "–",
                "elites": len(e),
            }
        )
    sec.table(pd.DataFrame(rows), "groups", "Groups (emotions or simulations) and samples")
    sec.bullets([f"Note: {n}" for n in ds.notes])
    sec.data["samples"] = {r["group"]: r["samples"] for r in rows}
    return sec


def _errors(ds: Dataset, out: Path) -> Section:
    sec = Section(out)
    sec.heading("Error distributions per generation")
    panels = {g: ds.errors(g) for g in ds.groups}
    panels = {g: e for g, e in panels.items() if np.isfinite(e).any()}
    if not panels:
        sec.paragraph("No errors: no group has a complete sample with weights (no proxy target).")
        return sec
    tables, kls = [], {}
    for g, e in panels.items():
        s = generation_summary(e)
        s.insert(0, "group", g)
        tables.append(s)
        ok = e[np.isfinite(e).all(axis=1)]
        if len(ok) >= 2 and ds.generations >= 1:
            kls[g] = kl_per_generation(ok)
    table = pd.concat(tables, ignore_index=True)
    sec.table(table, "errors_by_generation", "Elite error per generation (CD)")
    fig = plots.generation_distributions(panels, sec.figures / "error_distributions.png")
    sec.figure(fig, "Per-generation distributions of the elite's error (violins; mean ± sd).")
    sec.data["final_error"] = {
        g: {"mean": float(np.nanmean(e[:, -1])), "sd": float(np.nanstd(e[:, -1], ddof=1))}
        for g, e in panels.items()
        if np.isfinite(e[:, -1]).sum() > 1
    }
    if kls:
        rows = [
            {"group": g, "generation": i + 1, "kl_nats": float(v)}
            for g, kl in kls.items()
            for i, v in enumerate(kl)
        ]
        sec.paragraph(
            "KL(P_g ‖ P_g−1) between consecutive generations' error distributions: Gaussian "
            "kernel density estimates (Scott's bandwidth, at least 0.005) on a common 512-point "
            "grid, trapezoid rule, in nats. Samples complete through every generation only."
        )
        sec.table(
            pd.DataFrame(rows).pivot(index="generation", columns="group", values="kl_nats"),
            "kl_by_generation",
            "KL divergence between consecutive generations [nats]",
            index=True,
            data=pd.DataFrame(rows),
        )
        sec.figure(plots.kl_curves(kls, sec.figures / "kl.png"), "KL per generation (log scale).")
        sec.data["kl"] = {g: kl.tolist() for g, kl in kls.items()}
    return sec


def _repeatability(ds: Dataset, out: Path) -> Section:
    sec = Section(out)
    sec.heading("Initial bias and repeatability")
    rows = []
    for g in ds.groups:
        row: dict[str, Any] = {"group": g}
        b = ds.bias.loc[ds.bias["group"] == g, "best_initial_error"].to_numpy(dtype=np.float64)
        row["bias mean"] = float(b.mean()) if len(b) else np.nan
        row["bias sd"] = float(b.std(ddof=1)) if len(b) > 1 else np.nan
        fw = ds.final_weights(g) if ds.has_weights else np.zeros((0, 0))
        row["final faces"] = len(fw)
        shares = repeatability_bins(fw) if len(fw) >= 2 else np.full(4, np.nan)
        for label, v in zip(BIN_LABELS, shares, strict=True):
            row[f"{label} %"] = 100 * float(v)
        rows.append(row)
    table = pd.DataFrame(rows)
    sec.paragraph(
        "Bias: CD of the best generation-0 face to the (proxy) target — 1.0 means no bias. "
        "Bins: shares of all pairs of final faces by their CD (the paper's Table III)."
    )
    data = table.rename(
        columns={"bias mean": "bias_mean", "bias sd": "bias_sd", "final faces": "n_final_faces"}
        | {f"{b} %": tidy.machine_name(f"pct pairs cd {b}") for b in BIN_LABELS}
    )
    sec.table(
        table,
        "repeatability",
        "Target bias and inter-sample CD bins of the final faces",
        data=data,
    )
    bins_only = table.set_index("group")[[f"{b} %" for b in BIN_LABELS]].dropna()
    if len(bins_only):
        bins_only.columns = list(BIN_LABELS)
        sec.figure(
            plots.bins(bins_only, sec.figures / "repeatability.png"),
            "Inter-sample CD of final faces, by bin.",
        )
    sec.data["repeatability"] = table.to_dict(orient="records")
    return sec


def _ratings(ds: Dataset, out: Path) -> Section:
    sec = Section(out)
    r = ds.ratings
    if r is None or r.empty or "value" not in r.columns:
        return sec
    sec.heading("Ratings of the final faces")
    key = r["emotion"].astype(str) if "emotion" in r.columns else pd.Series("all", index=r.index)
    table = r.groupby(key)["value"].agg(["count", "mean", "std", "min", "max"]).reset_index()
    table.columns = ["group", "n", "mean", "sd", "min", "max"]
    sec.table(table, "ratings", "Ratings (1 = not at all … points = perfectly)")
    sec.data["ratings"] = table.to_dict(orient="records")
    return sec
