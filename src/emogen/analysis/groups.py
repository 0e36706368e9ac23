"""Groups of participants (a ``group`` column of the participant table: clinical against
control, …): do their faces of an emotion differ in location, and in dispersion?

The participant is the unit: each participant's faces of an emotion (over identities and
repetitions) are first averaged into their **mean face** (genes), and every test permutes
participants between groups, never faces.

* **Location** (a one-way PERMANOVA on the mean faces, Anderson 2001, with Euclidean distance
  in gene space): R² = SS_between / SS_total of the participants' mean faces, its p from
  ``permutations`` relabellings of participants (p = (1 + #{R²_perm ≥ R²}) / (1 +
  permutations)); with two groups also the ED between the group centroids. Intervals: the
  percentile bootstrap over participants resampled within groups (2000 draws).
* **Dispersion** (PERMDISP, Anderson 2006): each participant's distance to their group's
  centroid; the F of a one-way ANOVA on those distances, its p from permuting the distances
  between groups; effect: the difference (two groups) or range of the groups' mean distances.
  A location test alone cannot tell a shifted group from a more variable one; a dispersion
  difference also makes PERMANOVA's p liberal, so both are reported.

Assumptions: participants independent and exchangeable between groups under the null;
Euclidean distances between mean faces (genes in [0, 1]).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.analysis.results import Section
from emogen.errors import DataError

if TYPE_CHECKING:
    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.analysis.people import People

MIN_PER_GROUP = 3


def mean_faces(people: People, emotion: str, column: str = "group") -> pd.DataFrame:
    """One row per participant with faces of ``emotion``: their ``column`` value and mean genes."""
    f = people.faces[people.faces["emotion"] == emotion]
    genes = list(people.genes)
    means = f.groupby("participant_id")[genes].mean()
    means.insert(0, column, f.groupby("participant_id")[column].first())
    return means.reset_index()


def _r2(x: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """R² of group ``labels`` (P, n) int codes over points ``x`` (n, d), one per labelling."""
    labels = np.atleast_2d(labels)
    total = np.sum((x - x.mean(axis=0)) ** 2)
    k = int(labels.max()) + 1
    onehot = labels[..., None] == np.arange(k)  # (P, n, k)
    counts = onehot.sum(axis=1)  # (P, k)
    sums = np.einsum("pnk,nd->pkd", onehot, x)
    ssb = np.sum(np.sum(sums**2, axis=2) / np.maximum(counts, 1), axis=1)
    ssb -= len(x) * np.sum(x.mean(axis=0) ** 2)
    return np.asarray(ssb / total)


def _dispersion_f(z: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """One-way ANOVA F of distances ``z`` (n,) by ``labels`` (P, n), one per labelling."""
    labels = np.atleast_2d(labels)
    k = int(labels.max()) + 1
    onehot = labels[..., None] == np.arange(k)
    counts = onehot.sum(axis=1)
    means = np.einsum("pnk,n->pk", onehot, z) / np.maximum(counts, 1)
    ssb = np.sum(counts * (means - z.mean()) ** 2, axis=1)
    ssw = np.sum((z[None, :] - np.take_along_axis(means, labels, axis=1)) ** 2, axis=1)
    n = len(z)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray((ssb / (k - 1)) / (ssw / (n - k)))


def centroid_distances(x: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """Each point's Euclidean distance to its group's centroid."""
    cent = np.stack([x[codes == g].mean(axis=0) for g in range(int(codes.max()) + 1)])
    return np.asarray(np.linalg.norm(x - cent[codes], axis=1))


def compare_groups(
    x: np.ndarray,
    groups: np.ndarray,
    *,
    rng: np.random.Generator,
    permutations: int = 4999,
    draws: int = 2000,
) -> dict[str, Any]:
    """Location and dispersion tests of participants' mean faces ``x`` (n, d) by ``groups``."""
    names, codes = np.unique(np.asarray(groups).astype(str), return_inverse=True)
    sizes = np.bincount(codes)
    if len(names) < 2 or sizes.min() < MIN_PER_GROUP:
        raise DataError(
            f"a group comparison needs 2 or more groups of at least {MIN_PER_GROUP} "
            f"participants; got {dict(zip(names.tolist(), sizes.tolist(), strict=True))}"
        )
    perms = np.stack([rng.permutation(codes) for _ in range(permutations)])
    r2 = float(_r2(x, codes)[0])
    p_loc = (1 + np.sum(_r2(x, perms) >= r2 - 1e-12)) / (1 + permutations)
    z = centroid_distances(x, codes)
    f = float(_dispersion_f(z, codes)[0])
    p_disp = (1 + np.sum(_dispersion_f(z, perms) >= f - 1e-12)) / (1 + permutations)
    boot = _bootstrap(x, codes, rng, draws)
    out: dict[str, Any] = {
        "groups": " | ".join(f"{n} ({s})" for n, s in zip(names, sizes, strict=True)),
        "participants": len(x),
        "r2": r2,
        "r2_low": boot["r2"][0],
        "r2_high": boot["r2"][1],
        "p_location": float(p_loc),
        "dispersion_f": f,
        "p_dispersion": float(p_disp),
        **{f"dispersion_{n}": float(z[codes == i].mean()) for i, n in enumerate(names)},
    }
    if len(names) == 2:
        out["centroid_ed"] = float(np.linalg.norm(x[codes == 0].mean(0) - x[codes == 1].mean(0)))
        out["centroid_ed_low"], out["centroid_ed_high"] = boot["ed"]
        out["dispersion_difference"] = float(z[codes == 1].mean() - z[codes == 0].mean())
    return out


def _bootstrap(
    x: np.ndarray, codes: np.ndarray, rng: np.random.Generator, draws: int
) -> dict[str, tuple[float, float]]:
    """Percentile 95% intervals of R² and (two groups) the centroid ED, participants resampled
    within their groups."""
    members = [np.flatnonzero(codes == g) for g in range(int(codes.max()) + 1)]
    r2, ed = np.empty(draws), np.empty(draws)
    for b in range(draws):
        idx = np.concatenate([rng.choice(m, size=len(m)) for m in members])
        xb, cb = x[idx], codes[idx]
        r2[b] = _r2(xb, cb)[0]
        if len(members) == 2:
            ed[b] = np.linalg.norm(xb[cb == 0].mean(0) - xb[cb == 1].mean(0))
    q = [2.5, 97.5]
    return {"r2": tuple(np.percentile(r2, q)), "ed": tuple(np.percentile(ed, q))}


def groups_section(
    people: People, folder: Path, opts: AnalysisOptions, column: str = "group"
) -> Section:
    """The report's group comparison per emotion (nothing without a participant table)."""
    report = Section(folder)
    if column not in people.participant_columns:
        return report
    report.heading(f"Groups of participants ('{column}')")
    rng = np.random.default_rng(np.random.SeedSequence(opts.seed, spawn_key=(0x6A,)))
    rows, notes = [], []
    for emotion in people.emotions:
        m = mean_faces(people, emotion, column).dropna(subset=[column])
        try:
            res = compare_groups(m[list(people.genes)].to_numpy(), m[column].to_numpy(), rng=rng)
        except DataError as exc:
            notes.append(f"{emotion}: {exc}")
            continue
        rows.append({"emotion": emotion, **res})
    report.paragraph(
        "Unit: the participant (their mean face of the emotion, over identities and "
        "repetitions). Location: one-way PERMANOVA (Anderson 2001) on the mean faces, Euclidean "
        "distance in gene space, R² with p from 4999 permutations of participants between "
        "groups; dispersion: PERMDISP (Anderson 2006), ANOVA F of each participant's distance "
        "to their group's centroid, p from permuting those distances. 95% percentile bootstrap "
        f"intervals, participants resampled within groups (seed {opts.seed}). Not corrected "
        "for the number of emotions tested; assumptions: participants independent, "
        "exchangeable between groups under the null."
    )
    report.bullets([f"Skipped {n}" for n in notes])
    if rows:
        table = pd.DataFrame(rows)
        report.table(
            table, "participant_groups", f"Groups ('{column}') per emotion: location and dispersion"
        )
        report.data["groups"] = rows
    for row in rows:
        e = row["emotion"]
        report.add_test(
            f"groups.location[{e}]",
            row,
            test="PERMANOVA (4999 permutations of participants)",
            p=row["p_location"],
            n=row["participants"],
            estimate=row["r2"],
            interval=(row["r2_low"], row["r2_high"]),
            level=0.95,
            effect=("R²", row["r2"], row["r2_low"], row["r2_high"]),
        )
        report.add_test(
            f"groups.dispersion[{e}]",
            row,
            test="PERMDISP (permuted distances to the centroid)",
            p=row["p_dispersion"],
            n=row["participants"],
            statistic=row["dispersion_f"],
        )
    return report
