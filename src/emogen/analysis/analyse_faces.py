"""``emogen analyse``'s sections on the faces themselves: separability of the groups (PCA +
GMM) and the prototypes (each participant's mean final face, group means, renders)."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.data import Dataset
from emogen.analysis.prototypes import group_means, participant_prototypes, top_weights
from emogen.analysis.report import Content
from emogen.analysis.results import Section
from emogen.analysis.separability import gmm_separability
from emogen.analysis.separability_figure import separability_figure
from emogen.errors import EmoGenError

if TYPE_CHECKING:
    from emogen.appearance.identities import Identity
    from emogen.model.face import FaceModel

log = logging.getLogger(__name__)


def separability_section(ds: Dataset, out: Path, opts: AnalysisOptions) -> Section:
    """PCA + GMM: can the groups' final faces be told apart (descriptive; no test)?"""
    report = Section(out)
    report.heading("Separability of the groups (PCA + GMM)")
    if not ds.has_weights or len(ds.groups) < 2:
        report.paragraph("Skipped: needs face weights and at least two groups.")
        return report
    final = ds.final
    counts = final.groupby("group").size().reindex(list(ds.groups), fill_value=0)
    if (counts < 2).any() or counts.sum() < 2 * len(ds.groups) + 1:
        report.paragraph(
            f"Skipped: too few final faces per group for a {len(ds.groups)}-component mixture "
            f"({', '.join(f'{g}: {n}' for g, n in counts.items())}; at least 2 per group)."
        )
        return report
    x = final[list(ds.columns)].to_numpy(dtype=np.float64)
    labels = final["group"].map({g: i for i, g in enumerate(ds.groups)}).to_numpy()
    targets = np.stack([ds.targets[g] for g in ds.groups]) if ds.targets else None
    try:
        sep = gmm_separability(
            x, labels, ds.groups, targets=targets, n_pca=opts.gmm_dims, seed=opts.seed
        )
    except EmoGenError as exc:
        report.paragraph(f"Skipped: {exc}")
        return report
    report.paragraph(
        f"PCA of the final faces{' and the targets' if targets is not None else ''}; a "
        f"{len(ds.groups)}-component Gaussian mixture in the first {sep.n_pca} components "
        f"({sep.explained_variance:.0%} of the variance). Clusters are named after the groups "
        'whose mean face they contain ("unnamed": none). Accuracy: share of faces in the '
        f"cluster of their own group alone = **{sep.accuracy:.1%}**; adjusted Rand index "
        f"{sep.ari:.3f}; one cluster per group: {'yes' if sep.one_to_one else 'no'}."
    )
    long = sep.confusion.to_numpy()
    data = pd.DataFrame(
        [
            {"group": g, "cluster": str(c), "n_samples": int(long[i, j])}
            for i, g in enumerate(sep.groups)
            for j, c in enumerate(sep.confusion.columns)
        ]
    )
    report.table(
        sep.confusion,
        "confusion",
        "GMM classification of each group's final faces",
        index=True,
        data=data,
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
    _mixture_warning(report, len(x), len(ds.groups), sep.n_pca, ds.kind)
    report.figure(
        separability_figure(sep, report.figures / "separability.png"),
        "Final faces in the first two PCA components; GMM components (1σ, 2σ), group "
        "means (×) and targets (★).",
    )
    report.data["separability"] = {
        "accuracy": sep.accuracy,
        "ari": sep.ari,
        "one_to_one": sep.one_to_one,
        "n_pca": sep.n_pca,
    }
    return report


def _mixture_warning(report: Content, n: int, k: int, d: int, kind: str) -> None:
    """Say loudly when the mixture has too many parameters for the faces, and that the
    clustering is descriptive (faces, not participants, are its points)."""
    params = k * (d + d * (d + 1) // 2) + (k - 1)
    if n < 5 * params:
        report.paragraph(
            f"**Warning: {n} faces for a {k}-component mixture with {params} parameters** (a "
            f"full covariance per component in {d} dimensions): fewer than 5 faces per "
            "parameter, so the clusters are unstable; read them as a description at most."
        )
    if kind == "study":
        report.paragraph(
            "This clustering describes faces (a participant's repeated faces are several "
            "points); it is not a test. The participant-level tests are in the analyses of "
            "participants below."
        )


def prototypes_section(
    ds: Dataset,
    out: Path,
    opts: AnalysisOptions,
    model: FaceModel | None,
    identities: dict[str, Identity] | None = None,
) -> Section:
    """Participants' prototypes, group means and their renders; ``identities``: the identity
    each group was made on (a study's), to draw its mean face as participants saw it."""
    report = Section(out)
    report.heading("Prototypes and mean faces")
    if not ds.has_weights or ds.final.empty:
        report.paragraph("Skipped: needs final faces with weights.")
        return report
    cols = list(ds.columns)
    protos = participant_prototypes(ds.final, cols)
    means = group_means(protos, cols)
    if ds.kind == "study":
        report.csv(protos.rename(columns={c: f"w_{c}" for c in cols}), "prototypes")
        show = protos[["group", "participant", "n_trials"]].copy()
        show["largest weights"] = [top_weights(r, cols) for r in protos[cols].to_numpy()]
        report.table(
            show,
            None,
            "Per-participant prototypes: mean final face per group "
            "(full weights in tables/prototypes.csv)",
        )
    mean_rows, data = _group_means_tables(ds, means, cols)
    report.table(
        pd.DataFrame(mean_rows), "group_means", "Group mean faces (mean of prototypes)", data=data
    )
    report.data["group_means"] = {g: m.tolist() for g, m in means.items()}
    if model is None or not opts.render:
        report.paragraph("Renders skipped (no face model, or --no-render).")
        return report
    from emogen.analysis.face_sheets import Panel, face_sheet, heatmap_sheet, model_weights

    try:
        mw = {g: model_weights(m, cols, model) for g, m in means.items()}
        on = [(identities or {}).get(g) for g in mw]
        sheet = face_sheet(
            model,
            np.stack(list(mw.values())),
            list(mw),
            report.figures / "mean_faces.png",
            size=opts.render_size,
            identities=on,
        )
        drawn = (
            " on the identity it was made on (shape and appearance, as participants saw it)"
            if any(i is not None for i in on)
            else ""
        )
        report.figure(sheet, f"Mean final face of each group{drawn}.")
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
    return report


def _group_means_tables(
    ds: Dataset, means: dict[str, np.ndarray], cols: list[str]
) -> tuple[list[dict[str, object]], pd.DataFrame]:
    """The group means for the report (largest weights; CD and norm ratio to the target) and
    for machines (every weight ``w_<shape>``, full precision)."""
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
    data = pd.DataFrame(
        [
            {
                "group": g,
                **(
                    {
                        "cd_mean_target": r["CD(mean, target)"],
                        "norm_ratio_mean_target": r["|mean| / |target|"],
                    }
                    if ds.targets
                    else {}
                ),
                **{f"w_{c}": float(v) for c, v in zip(cols, means[g], strict=True)},
            }
            for g, r in zip(means, mean_rows, strict=True)
        ]
    )
    return mean_rows, data
