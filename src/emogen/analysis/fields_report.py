"""The report section on perceptive fields (:mod:`emogen.analysis.fields`): the face space,
the fields and their bandwidth, their overlap between participants, whether a participant's
field is their own (split halves), clusters of participants, and maps."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from scipy import stats

from emogen.analysis import field_maps
from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.field_clusters import Clustering, cluster_fields
from emogen.analysis.fields import (
    Fields,
    bhattacharyya,
    face_space,
    field_individuality,
    overlaps,
    perceptive_fields,
)
from emogen.analysis.people import People
from emogen.analysis.report import Content
from emogen.analysis.results import Section
from emogen.errors import EmoGenError

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

log = logging.getLogger(__name__)

#: Fewest participants with fields for the between-participant analyses.
MIN_PARTICIPANTS = 6
#: Most participants on the contact sheets (a random sample beyond): every face rendered
#: costs CPU — at 336 participants the sheets of all 2688 mean faces took 140 s of CPU, more
#: than the 2-minute goal of the whole analysis (benchmarks/bench_analyse.py, #41) — and a
#: sheet of 672 faces per emotion is too long to look at.
SHEET_PARTICIPANTS = 48


def fields_section(
    people: People, folder: Path, opts: AnalysisOptions, model: FaceModel | None
) -> Section:
    """Perceptive fields of every participant per emotion, their overlap and clusters."""
    report = Section(folder)
    report.heading("Perceptive fields")
    counts = people.faces.groupby(["participant_id", "emotion"]).size()
    if people.n_participants < MIN_PARTICIPANTS or counts.max() < 2:
        report.paragraph(
            f"Skipped: perceptive fields need at least {MIN_PARTICIPANTS} participants with two "
            f"or more final faces of an emotion; this study has {people.n_participants} "
            f"participant(s) with at most {counts.max()} face(s) per emotion."
        )
        return report
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(opts.seed)
    space = face_space(people)
    fields = perceptive_fields(people, space)
    out: dict[str, Any] = {"components": space.k, "variance": float(space.explained.sum())}
    _describe(fields, counts, report, out)
    # BLAS on one thread: the matrices are small and many (100 null studies); on the busy
    # 2-core machine one null study at 336 took 4.8 s wall, 0.69 s CPU on BLAS's default
    # threads and 0.28 s, 0.03 s on one (benchmarks/bench_fields.py, load 12)
    with threadpool_limits(limits=1, user_api="blas"):
        matrices = _overlaps(fields, report, rng, out)
        _individuality(people, fields, report, opts, out)
        clustering = _clusters(fields, report, opts, rng, out)
    order = list(clustering.participants) if clustering else []
    if clustering is not None and clustering.structure:
        order = [p for _, p in sorted(zip(clustering.labels, clustering.participants, strict=True))]
    order += sorted({p for m in matrices.values() for p in m.index} - set(order))
    report.figure(
        field_maps.field_heatmaps(fields, report.figures / "fields_pc_maps.png"),
        "Where each emotion's fields lie: the population field (every participant's field "
        "weighing the same) on the face space's first two components, relative density; white "
        "dots: each participant's field centre.",
    )
    report.figure(
        field_maps.overlap_heatmaps(matrices, order, report.figures / "fields_overlap.png"),
        "Overlap of every pair of participants' fields, per emotion (participants ordered by "
        "cluster when there are clusters, else by id).",
    )
    _sheets(people, report, opts, model)
    report.data["fields"] = out
    return report


def _describe(fields: Fields, counts: pd.Series, report: Content, out: dict[str, Any]) -> None:
    sp = fields.space
    n_min, n_med = int(counts.min()), float(counts.median())
    report.paragraph(
        f"Face space: the study's own PCA of all {sum(len(x) for x in fields.points.values())} "
        f"final faces' genes; the first {sp.k} components, {100 * sp.explained.sum():.0f} % of "
        "the gene variance, unwhitened (distances are gene distances within that subspace). A "
        "participant's field of an emotion is a Gaussian kernel density estimate of their "
        "final faces of it in this space (after 'Expression perceptive fields', Communications "
        "Psychology 2024). Participants made "
        f"{n_min}–{int(counts.max())} faces per emotion (median {n_med:g}): far too few for a "
        "bandwidth of their own, so one bandwidth per emotion is shared by every participant's "
        "field and chosen by leave-one-out cross-validated likelihood pooled over all "
        "participants' fields. A field therefore says where a participant's faces lie and how "
        "they spread, smoothed by the study's typical within-participant scatter; with so few "
        "faces it cannot resolve a multimodal field of one person."
    )
    rows = []
    for e in fields.emotions:
        cv = fields.cv[e]
        edge = bool(len(cv)) and bool(cv["chosen"].iloc[0] or cv["chosen"].iloc[-1])
        rows.append(
            {
                "emotion": e,
                "n_fields": len(fields.participants(e)),
                "components": sp.k,
                "bandwidth": fields.bandwidth[e],
                "at_grid_edge": edge,
            }
        )
    report.table(
        pd.DataFrame(rows), "fields_bandwidth", "Bandwidth (kernel SD, gene units) per emotion"
    )
    report.table(fields.table(), "fields_fields", "Each participant's field: size, centre, spread")
    out["bandwidth"] = {r["emotion"]: r["bandwidth"] for r in rows}


def _overlaps(
    fields: Fields, report: Content, rng: np.random.Generator, out: dict[str, Any]
) -> dict[str, pd.DataFrame]:
    matrices, long = {}, []
    for e in fields.emotions:
        m = overlaps(fields, e)
        matrices[e] = m
        who = list(m.index)
        pts = [fields.points[(p, e)] for p in who]
        bc, mn = bhattacharyya(pts, fields.bandwidth[e], rng=rng)
        i, j = np.triu_indices(len(who), 1)
        long.append(
            pd.DataFrame(
                {
                    "emotion": e,
                    "participant_a": np.array(who)[i],
                    "participant_b": np.array(who)[j],
                    "overlap": m.to_numpy()[i, j],
                    "bhattacharyya": bc[i, j],
                    "overlap_min": mn[i, j],
                }
            )
        )
    table = pd.concat(long, ignore_index=True)
    shown = table.groupby("emotion")[["overlap", "bhattacharyya", "overlap_min"]].agg(
        ["mean", "median"]
    )
    shown.columns = [" ".join(map(str, c)) for c in shown.columns.to_list()]
    report.paragraph(
        "Overlap of two participants' fields p, q: the normalised probability-product kernel "
        "∫pq/√(∫p²∫q²) (Jebara, Kondor & Howard 2004), exact for Gaussian kernel densities, 1 "
        "for identical fields and 0 for disjoint ones; beside it the Bhattacharyya coefficient "
        "∫√(pq) and ∫min(p, q), by Monte Carlo (256 draws per field, SE < 0.05). The overlap "
        "is descriptive: each pair is a pair of participants, no test."
    )
    report.table(
        shown.reset_index(),
        None,
        "Overlap between participants' fields, per emotion "
        "(every pair in tables/fields_overlap.csv)",
    )
    _write_only(report, table, "fields_overlap")
    out["mean_overlap"] = table.groupby("emotion")["overlap"].mean().to_dict()
    return matrices


def _write_only(report: Content, table: pd.DataFrame, name: str) -> None:
    """A machine table under tables/ without showing it in the report (too many rows)."""
    from emogen import columns as tidy

    report.csv(tidy.machine_table(table), name)


def _individuality(
    people: People, fields: Fields, report: Section, opts: AnalysisOptions, out: dict[str, Any]
) -> None:
    ind = field_individuality(people, fields)
    if ind.empty:
        report.paragraph(
            "No split-half test of whether fields are the participant's own: it needs at least "
            "four faces per participant and emotion (two per half) from three participants."
        )
        return
    rows = []
    for e, part in ind.groupby("emotion"):
        diff = (part["self"] - part["others"]).to_numpy()
        res = stats.ttest_1samp(diff, 0.0)
        ci = res.confidence_interval(1 - opts.alpha)
        rows.append(
            {
                "emotion": e,
                "n_participants": len(part),
                "self_overlap": part["self"].mean(),
                "others_overlap": part["others"].mean(),
                "difference": diff.mean(),
                "ci_low": ci.low,
                "ci_high": ci.high,
                "t": res.statistic,
                "p": res.pvalue,
                "identified": part["identified"].mean(),
                "chance_identified": float((1 / part["n_candidates"]).mean()),
            }
        )
    table = pd.DataFrame(rows)
    report.paragraph(
        "Are fields the participant's own? Each participant's faces of an emotion are split "
        "into two halves (alternately, ordered by identity and repetition); the field of one "
        "half is compared with the field of their other half (self) and with everyone else's "
        "other halves (others, mean). Unit: participant; test: paired t-test of self − others "
        f"over participants, {100 * (1 - opts.alpha):.0f} % CI (assumes the differences are "
        "roughly normal or the sample large; participants independent). 'identified': share "
        "of participants whose own other half overlaps best (chance 1 / participants)."
    )
    report.table(table, "fields_individuality", "Split-half overlap: self against others")
    _write_only(report, ind, "fields_individuality_participants")
    out["individuality"] = table.set_index("emotion")[["difference", "p", "identified"]].to_dict(
        orient="index"
    )
    for row in rows:
        name, record = (
            f"fields.individuality.{row['emotion']}",
            out["individuality"][row["emotion"]],
        )
        if not np.isfinite(row["p"]):
            reason = f"{row['n_participants']} participant(s), or no spread: no t"
            report.not_run(name, reason, record, n=row["n_participants"])
            continue
        report.add_test(
            name,
            record,
            test="paired t (self − others overlap)",
            p=row["p"],
            n=row["n_participants"],
            statistic=row["t"],
            df=row["n_participants"] - 1,
            estimate=row["difference"],
            interval=(row["ci_low"], row["ci_high"]),
            level=1 - opts.alpha,
        )


def _clusters(
    fields: Fields,
    report: Section,
    opts: AnalysisOptions,
    rng: np.random.Generator,
    out: dict[str, Any],
) -> Clustering | None:
    try:
        c = cluster_fields(fields, rng=rng, alpha=opts.alpha)
    except EmoGenError as exc:
        report.paragraph(f"No clustering of participants: {exc}.")
        return None
    report.paragraph(
        f"Clusters of participants by their fields over all emotions ({len(c.participants)} "
        "participants with a field of every emotion): distance d² = 2 − 2·overlap averaged "
        "over emotions, spectral clustering of the mean overlap into 2 … "
        f"{max(c.silhouettes, default=2)} clusters, the number by the largest mean silhouette. "
        "Test (unit: participant): is that silhouette larger than in studies of one population "
        "— field centres redrawn from one Gaussian with the observed mean and covariance, each "
        f"participant's own scatter kept ({c.n_null} such studies; after SigClust, Liu et al. "
        "2008)? Assumes one population would look Gaussian in the face space. Silhouettes of "
        "fields are small in absolute terms (fields in many dimensions barely overlap); judge "
        f"them against the null. Seed {opts.seed}."
    )
    sil = pd.DataFrame({"k": list(c.silhouettes), "silhouette": list(c.silhouettes.values())})
    report.table(sil, "fields_silhouettes", "Mean silhouette per number of clusters")
    verdict = (
        f"Structure: {c.k} clusters (best silhouette {c.silhouette:.3f}, p = {c.p_value:.3f} "
        f"< α = {opts.alpha})."
        if c.structure
        else f"No structure: the best silhouette ({c.silhouette:.3f} at k = {c.k}) is not "
        f"larger than in one-population studies (p = {c.p_value:.3f} ≥ α = {opts.alpha}); no "
        "clusters are reported."
    )
    report.paragraph(verdict)
    table = c.table()
    if c.structure:
        report.table(
            table.groupby("cluster").size().rename("participants").reset_index(),
            None,
            "Participants per cluster",
        )
    _write_only(report, table, "fields_clusters")
    out["clusters"] = {
        "structure": c.structure,
        "k": c.k if c.structure else 1,
        "silhouette": c.silhouette,
        "p": c.p_value,
    }
    report.add_test(
        "fields.clusters",
        out["clusters"],
        test="one-population null of the best silhouette over k",
        p=c.p_value,
        n=len(c.participants),
        statistic=c.silhouette,
    )
    return c


def _sheets(
    people: People, report: Content, opts: AnalysisOptions, model: FaceModel | None
) -> None:
    if model is None or not opts.render:
        report.paragraph(
            "Contact sheets of the participants' faces skipped (no face model, or --no-render)."
        )
        return
    who = sorted(people.faces["participant_id"].astype(str).unique())
    shown = None
    if len(who) > SHEET_PARTICIPANTS:
        pick = np.random.default_rng(opts.seed).choice(len(who), SHEET_PARTICIPANTS, replace=False)
        shown = {who[i] for i in pick}
        report.paragraph(
            f"Contact sheets: {SHEET_PARTICIPANTS} of the {len(who)} participants, drawn at "
            f"random (seed {opts.seed}); every participant's field is in the tables above."
        )
    try:
        sheets, missing = field_maps.contact_sheets(
            people, model, report.figures, size=min(opts.render_size, 160), participants=shown
        )
    except EmoGenError as exc:
        log.warning("rendering failed: %s", exc)
        report.paragraph(f"Contact sheets failed: {exc}")
        return
    if missing:
        report.paragraph(
            f"Not rendered (identity unknown to the export and the presets): {', '.join(missing)}."
        )
    for e, path in sheets.items():
        report.figure(
            path,
            f"{e}: each participant's mean final face per identity, on the "
            "identity (shape and appearance) they made it on; (n) faces averaged.",
        )
