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
7. ratings (studies).

Everything lands in ``OUT``: ``index.html`` and ``README.md``, ``figures/*.png``,
``tables/*.csv`` and ``analysis.json`` (the headline numbers).
"""

from __future__ import annotations

import dataclasses
import json
import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.analysis import plots
from emogen.analysis.data import Dataset, load_dataset
from emogen.analysis.distributions import generation_summary, kl_per_generation
from emogen.analysis.noise import PAPER_NOISE, latent_spread_test, spread_test
from emogen.analysis.prototypes import group_means, participant_prototypes, top_weights
from emogen.analysis.repeatability import BIN_LABELS, repeatability_bins
from emogen.analysis.report import Report
from emogen.analysis.separability import gmm_separability
from emogen.config import PAPER_SELECTIONS, GAConfig, SimulationConfig
from emogen.errors import EmoGenError

if TYPE_CHECKING:
    from emogen.model.face import FaceModel
    from emogen.model.rig import Rig

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class AnalysisOptions:
    render: bool = True
    noise_runs: int = 500
    noise_draws: int = 2000
    seed: int = 1
    gmm_dims: float = 2
    alpha: float = 0.05
    ga: GAConfig | None = None  # the study's GA settings (default: inferred from the data)
    render_size: int = 256


@dataclass
class AnalysisResult:
    out: Path
    html: Path
    markdown: Path
    summary: dict[str, Any] = field(default_factory=dict)


def analyse(
    data: Path | Dataset,
    out: Path,
    *,
    model: FaceModel | None = None,
    options: AnalysisOptions | None = None,
) -> AnalysisResult:
    """Analyse ``data`` (a folder or a loaded :class:`Dataset`) into a report in ``out``."""
    opts = options or AnalysisOptions()
    ds = data if isinstance(data, Dataset) else load_dataset(Path(data))
    report = Report(f"EmoGen analysis: {ds.source.name}", Path(out))
    summary: dict[str, Any] = {"source": str(ds.source), "kind": ds.kind, "groups": list(ds.groups)}
    _overview(ds, report, summary)
    _errors(ds, report, summary)
    _repeatability(ds, report, summary)
    _separability(ds, report, summary, opts)
    _noise(ds, report, summary, opts, model)
    _prototypes(ds, report, summary, opts, model)
    _ratings(ds, report, summary)
    if ds.has_weights:
        ds.elites.to_csv(report.out / "tables" / "elites.csv", index=False)
    (report.out / "analysis.json").write_text(json.dumps(summary, indent=2, default=_json) + "\n")
    html_path, md_path = report.write()
    return AnalysisResult(report.out, html_path, md_path, summary)


def _json(o: object) -> object:
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


# ---- sections ------------------------------------------------------------------------------
def _overview(ds: Dataset, report: Report, summary: dict[str, Any]) -> None:
    report.paragraph(
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
    report.table(pd.DataFrame(rows), "groups", "Groups (emotions or simulations) and samples")
    report.bullets([f"Note: {n}" for n in ds.notes])
    summary["samples"] = {r["group"]: r["samples"] for r in rows}


def _errors(ds: Dataset, report: Report, summary: dict[str, Any]) -> None:
    report.heading("Error distributions per generation")
    panels = {g: ds.errors(g) for g in ds.groups}
    panels = {g: e for g, e in panels.items() if np.isfinite(e).any()}
    if not panels:
        report.paragraph(
            "No errors: no group has a complete sample with weights (no proxy target)."
        )
        return
    tables, kls = [], {}
    for g, e in panels.items():
        s = generation_summary(e)
        s.insert(0, "group", g)
        tables.append(s)
        ok = e[np.isfinite(e).all(axis=1)]
        if len(ok) >= 2 and ds.generations >= 1:
            kls[g] = kl_per_generation(ok)
    table = pd.concat(tables, ignore_index=True)
    report.table(table, "errors_by_generation", "Elite error per generation (CD)")
    fig = plots.generation_distributions(panels, report.figures / "error_distributions.png")
    report.figure(fig, "Per-generation distributions of the elite's error (violins; mean ± sd).")
    summary["final_error"] = {
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
        report.paragraph(
            "KL(P_g ‖ P_g−1) between consecutive generations' error distributions: Gaussian "
            "kernel density estimates (Scott's bandwidth, at least 0.005) on a common 512-point "
            "grid, trapezoid rule, in nats. Samples complete through every generation only."
        )
        report.table(
            pd.DataFrame(rows).pivot(index="generation", columns="group", values="kl_nats"),
            "kl_by_generation",
            "KL divergence between consecutive generations [nats]",
            index=True,
        )
        report.figure(
            plots.kl_curves(kls, report.figures / "kl.png"), "KL per generation (log scale)."
        )
        summary["kl"] = {g: kl.tolist() for g, kl in kls.items()}


def _repeatability(ds: Dataset, report: Report, summary: dict[str, Any]) -> None:
    report.heading("Initial bias and repeatability")
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
    report.paragraph(
        "Bias: CD of the best generation-0 face to the (proxy) target — 1.0 means no bias. "
        "Bins: shares of all pairs of final faces by their CD (the paper's Table III)."
    )
    report.table(table, "repeatability", "Target bias and inter-sample CD bins of the final faces")
    bins_only = table.set_index("group")[[f"{b} %" for b in BIN_LABELS]].dropna()
    if len(bins_only):
        bins_only.columns = list(BIN_LABELS)
        report.figure(
            plots.bins(bins_only, report.figures / "repeatability.png"),
            "Inter-sample CD of final faces, by bin.",
        )
    summary["repeatability"] = table.to_dict(orient="records")


def _separability(
    ds: Dataset, report: Report, summary: dict[str, Any], opts: AnalysisOptions
) -> None:
    report.heading("Separability of the groups (PCA + GMM)")
    if not ds.has_weights or len(ds.groups) < 2:
        report.paragraph("Skipped: needs face weights and at least two groups.")
        return
    final = ds.final
    counts = final.groupby("group").size().reindex(list(ds.groups), fill_value=0)
    if (counts < 2).any() or counts.sum() < 2 * len(ds.groups) + 1:
        report.paragraph(
            f"Skipped: too few final faces per group for a {len(ds.groups)}-component mixture "
            f"({', '.join(f'{g}: {n}' for g, n in counts.items())}; at least 2 per group)."
        )
        return
    x = final[list(ds.columns)].to_numpy(dtype=np.float64)
    labels = final["group"].map({g: i for i, g in enumerate(ds.groups)}).to_numpy()
    targets = np.stack([ds.targets[g] for g in ds.groups]) if ds.targets else None
    try:
        sep = gmm_separability(
            x, labels, ds.groups, targets=targets, n_pca=opts.gmm_dims, seed=opts.seed
        )
    except EmoGenError as exc:
        report.paragraph(f"Skipped: {exc}")
        return
    report.paragraph(
        f"PCA of the final faces{' and the targets' if targets is not None else ''}; a "
        f"{len(ds.groups)}-component Gaussian mixture in the first {sep.n_pca} components "
        f"({sep.explained_variance:.0%} of the variance). Clusters are named after the groups "
        'whose mean face they contain ("unnamed": none). Accuracy: share of faces in the '
        f"cluster of their own group alone = **{sep.accuracy:.1%}**; adjusted Rand index "
        f"{sep.ari:.3f}; one cluster per group: {'yes' if sep.one_to_one else 'no'}."
    )
    report.table(
        sep.confusion, "confusion", "GMM classification of each group's final faces", index=True
    )
    if sep.cluster_of_target:
        corr = pd.DataFrame(
            {
                "group": list(ds.groups),
                "cluster of group mean": [
                    sep.cluster_names[sep.cluster_of_group[g]] for g in ds.groups
                ],
                "cluster of target": [
                    sep.cluster_names[sep.cluster_of_target[g]] for g in ds.groups
                ],
            }
        )
        report.table(corr, "correspondence", "Cluster-to-target correspondence")
    report.bullets([f"Note: {n}" for n in sep.notes])
    report.figure(
        plots.separability(sep, report.figures / "separability.png"),
        "Final faces in the first two PCA components; GMM components (1σ, 2σ), group "
        "means (×) and targets (★).",
    )
    summary["separability"] = {
        "accuracy": sep.accuracy,
        "ari": sep.ari,
        "one_to_one": sep.one_to_one,
        "n_pca": sep.n_pca,
    }


def _shape_weights(
    weights: np.ndarray, columns: tuple[str, ...], shapes: tuple[str, ...]
) -> np.ndarray:
    index = {c: i for i, c in enumerate(columns)}
    out = np.zeros((len(weights), len(shapes)))
    for j, s in enumerate(shapes):
        if s in index:
            out[:, j] = weights[:, index[s]]
    return out


def noise_config(ds: Dataset, group: str, opts: AnalysisOptions) -> SimulationConfig:
    """The data's GA settings for simulating GA noise (target filled in by the caller)."""
    if ds.kind == "simulation" and group in ds.configs:
        cfg = dict(ds.configs[group])
        for k in ("target", "target_file", "target_row", "seed", "runs"):
            cfg.pop(k, None)
        cfg["metric"] = {"name": "cd"}
        cfg["noise_temperature"] = 0.0
        cfg["correct"] = False
        return SimulationConfig.model_validate(cfg | {"target": {"jawOpen": 1.0}})
    ga = opts.ga or GAConfig(
        generations=ds.generations,
        population_size=ds.population_size,
        max_selections=ds.population_size,
        random_faces=min(4, ds.population_size - 1),
    )
    observed = list(ds.selections)[: ds.generations + 1]
    schedule = observed if len(observed) == ds.generations + 1 else list(PAPER_SELECTIONS)
    schedule = [min(max(int(s), ga.min_selections), ga.max_selections) for s in schedule]
    return SimulationConfig(ga=ga, target={"jawOpen": 1.0}, selections=tuple(schedule))


def final_faces_simulator(
    config: SimulationConfig, rig: Rig, seed: int
) -> Callable[[np.ndarray, int], np.ndarray]:
    """``simulate(target (S,), runs) -> (runs, S)``: final elites of runs toward a target (full
    weights in the rig's shape order), with ``config``'s GA settings and a CD observer. Run r
    always uses the r-th seed spawned from ``seed``."""
    from emogen.rng import spawn_seeds
    from emogen.simulate.runner import build_problem
    from emogen.simulate.vectorised import simulate_runs

    problem = build_problem(
        config.model_copy(update={"runs": 1, "seed": seed}), rig, all_weights=True
    )
    seeds: list[int] = []

    def simulate(target: np.ndarray, runs: int) -> np.ndarray:
        if len(seeds) < runs:
            seeds[:] = spawn_seeds(seed, runs)
        t = np.asarray(target, dtype=np.float64)
        a = simulate_runs(
            dataclasses.replace(problem, target=t), np.arange(runs), np.array(seeds[:runs])
        )
        if a.weights is None:  # pragma: no cover
            raise EmoGenError("the simulation returned no weights")
        elite = np.argmax(a.rank[:, -1] == 0, axis=1)
        return np.asarray(a.weights[np.arange(runs), -1, elite])

    return simulate


def _noise(
    ds: Dataset,
    report: Report,
    summary: dict[str, Any],
    opts: AnalysisOptions,
    model: FaceModel | None,
) -> None:
    report.heading("GA noise: does each group's spread exceed it?")
    if not ds.has_weights:
        report.paragraph("Skipped: needs face weights.")
        return
    rng = np.random.default_rng(opts.seed)
    rows, notes = [], []
    candidates: list[dict[str, object]] = []
    for g in ds.groups:
        fw = ds.final_weights(g)
        if len(fw) < 2:
            notes.append(f"{g}: fewer than 2 final faces")
            continue
        if model is not None:
            faces = _shape_weights(fw, ds.columns, model.rig.shape_names)
            sim = final_faces_simulator(noise_config(ds, g, opts), model.rig, opts.seed)
            test, cands = latent_spread_test(
                faces,
                sim,
                group=g,
                alpha=opts.alpha,
                draws=opts.noise_draws,
                pool_runs=opts.noise_runs,
                rng=rng,
            )
            candidates += [{"group": g, **c.row()} for c in cands]
            chosen = next(c for c in cands if c.test.p_value == test.p_value)
            label = chosen.noise.label
        else:
            test = spread_test(
                fw, PAPER_NOISE, group=g, alpha=opts.alpha, draws=opts.noise_draws, rng=rng
            )
            label = PAPER_NOISE.label
        row = test.row()
        row["GA noise μ ± σ (to target)"] = label
        rows.append(row)
    report.paragraph(
        "Spread of a group = mean CD of its final faces to their mean (the proxy target). GA "
        "noise = the same statistic on random subsets of equal size from the final faces of "
        "simulated runs with one consistent target and the data's GA settings. The latent target "
        "is the least favourable of the sparse-to-dense candidates that reproduce the group's mean "
        "face (see emogen.analysis.noise); one-sided test at "
        f"α = {opts.alpha}. The paper's threshold for its model is {PAPER_NOISE.label} (CD to "
        "the true target)."
        + ("" if model is not None else " No face model was given: tested against the paper's μ.")
        + (
            " The data carry corrective weights: the test compares shape weights only "
            "(correctives are left out)."
            if model is not None and set(ds.columns) - set(model.rig.shape_names)
            else ""
        )
    )
    report.bullets([f"Skipped {n}" for n in notes])
    if rows:
        table = pd.DataFrame(rows)
        report.table(table, "spread_test", "Group spread against GA noise")
        report.figure(
            plots.spread(table, report.figures / "spread.png"),
            "Mean proxy error of each group against GA noise at the same n.",
        )
        summary["spread_test"] = rows
    if candidates:
        report.table(
            pd.DataFrame(candidates),
            "spread_candidates",
            "Latent-target candidates per group (τ: weights below τ × max zeroed)",
        )


def _prototypes(
    ds: Dataset,
    report: Report,
    summary: dict[str, Any],
    opts: AnalysisOptions,
    model: FaceModel | None,
) -> None:
    report.heading("Prototypes and mean faces")
    if not ds.has_weights or ds.final.empty:
        report.paragraph("Skipped: needs final faces with weights.")
        return
    cols = list(ds.columns)
    protos = participant_prototypes(ds.final, cols)
    means = group_means(protos, cols)
    if ds.kind == "study":
        protos.to_csv(report.out / "tables" / "prototypes.csv", index=False)
        show = protos[["group", "participant", "n_trials"]].copy()
        show["largest weights"] = [top_weights(r, cols) for r in protos[cols].to_numpy()]
        report.table(
            show,
            None,
            "Per-participant prototypes: mean final face per group "
            "(full weights in tables/prototypes.csv)",
        )
    mean_rows: list[dict[str, object]] = [
        {"group": g, "largest weights of the mean face": top_weights(m, cols, 8)}
        for g, m in means.items()
    ]
    if ds.targets:
        from emogen.metrics import cosine_distance

        for r in mean_rows:
            t = ds.targets[str(r["group"])]
            r["CD(mean, target)"] = float(cosine_distance(means[str(r["group"])], t))
            r["|mean| / |target|"] = float(
                np.linalg.norm(means[str(r["group"])]) / np.linalg.norm(t)
            )
    report.table(pd.DataFrame(mean_rows), "group_means", "Group mean faces (mean of prototypes)")
    summary["group_means"] = {g: m.tolist() for g, m in means.items()}
    if model is None or not opts.render:
        report.paragraph("Renders skipped (no face model, or --no-render).")
        return
    from emogen.analysis.heatmaps import Panel, face_sheet, heatmap_sheet, model_weights

    try:
        mw = {g: model_weights(m, cols, model) for g, m in means.items()}
        sheet = face_sheet(
            model,
            np.stack(list(mw.values())),
            list(mw),
            report.figures / "mean_faces.png",
            size=opts.render_size,
        )
        report.figure(sheet, "Mean final face of each group.")
        neutral = np.zeros(model.n_shapes)
        if ds.targets:
            panels = [Panel(g, mw[g], model_weights(ds.targets[g], cols, model)) for g in mw]
            caption = "Distance (cm) of each group's mean final face to its target (Fig. 9)."
        else:
            panels = [Panel(g, mw[g], neutral) for g in mw]
            caption = "Distance (cm) of each group's mean final face from the neutral face."
        stats = heatmap_sheet(
            model, panels, report.figures / "mean_face_heatmaps.png", size=opts.render_size
        )
        report.figure(report.figures / "mean_face_heatmaps.png", caption)
        report.table(stats, "mean_face_distances", "Vertex distances of the mean faces (cm)")
    except EmoGenError as exc:
        log.warning("rendering failed: %s", exc)
        report.paragraph(f"Renders failed: {exc}")


def _ratings(ds: Dataset, report: Report, summary: dict[str, Any]) -> None:
    r = ds.ratings
    if r is None or r.empty or "value" not in r.columns:
        return
    report.heading("Ratings of the final faces")
    key = r["emotion"].astype(str) if "emotion" in r.columns else pd.Series("all", index=r.index)
    table = r.groupby(key)["value"].agg(["count", "mean", "std", "min", "max"]).reset_index()
    table.columns = ["group", "n", "mean", "sd", "min", "max"]
    report.table(table, "ratings", "Ratings (1 = not at all … points = perfectly)")
    summary["ratings"] = table.to_dict(orient="records")
