"""Per-gene inference with the participant as the unit: which genes differ between emotions
(within participants) and between groups of participants (a participant table's column).

Every participant's final faces are first averaged per emotion (over identities and
repetitions): one value per participant × emotion × gene (:func:`participant_gene_means`).

* **Emotions** (:func:`emotion_gene_tests`): every pair of emotions (a, b); the participant's
  difference mean_a − mean_b per gene; a sign-flip permutation test of the studentised mean
  difference (paired, :func:`emogen.analysis.permutation.paired_signflip`).
* **Groups** (:func:`group_gene_tests`): per emotion and gene, the difference between two
  groups' participant means; a Welch-t permutation test relabelling participants
  (:func:`emogen.analysis.permutation.group_permutation`). More than two groups: every pair of
  groups, max-T within the pair, Bonferroni over the pairs.

Family-wise control: max-T over every gene × contrast of a table (``p_maxt``), and separately
Benjamini–Hochberg FDR over the same family (``q_bh``). Effect sizes: the mean difference (gene
units: a gene in [0, 1]) with an interval over participants that inverts a permutation test
(paired: sign flips; groups: relabellings, a shift; Student's or Welch's t where there are too
few participants for a finite one). Gene values are
bounded and often exactly zero (a shape left off): no p-value here assumes normality, and the
tables give the share of participants who used the gene (participant mean > :data:`USED`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pandas as pd

from emogen.analysis.facs import facs_code, gene_base
from emogen.analysis.people import People
from emogen.analysis.permutation import (
    PermutationResult,
    group_permutation,
    paired_signflip,
    shift_interval,
    signflip_interval,
    t_mean_ci,
    welch_difference_ci,
)
from emogen.errors import ConfigError

#: A participant "uses" a gene for an emotion when their mean value of it exceeds this.
USED = 0.01


@dataclass(frozen=True)
class GeneTestOptions:
    """``permutations``: relabellings per test (exact enumeration when fewer exist);
    ``level``: CI level (1 − α)."""

    permutations: int = 5000
    level: float = 0.95


def participant_gene_means(people: People, by: tuple[str, ...] = ("emotion",)) -> pd.DataFrame:
    """One row per participant × ``by`` cell: ``participant_id``, ``by`` columns, ``n_faces`` and
    the mean of every gene column over the participant's final faces in that cell."""
    keys = ["participant_id", *by]
    f = people.faces
    means = f.groupby(keys, observed=True)[list(people.genes)].mean()
    count = f.groupby(keys, observed=True).size().rename("n_faces")
    return pd.concat([count, means], axis=1).reset_index()


def _cube(means: pd.DataFrame, genes: tuple[str, ...], emotions: list[str]) -> tuple:
    """(participants, emotions, genes) array of participants with every emotion."""
    wide = means.pivot(index="participant_id", columns="emotion", values=list(genes))
    wide = wide.dropna()
    cube = np.stack([wide[g][emotions].to_numpy(np.float64) for g in genes], axis=2)
    return cube, list(wide.index)


def emotion_gene_tests(
    people: People, opts: GeneTestOptions, *, rng: np.random.Generator
) -> pd.DataFrame:
    """Every gene × emotion pair, paired within participants (see the module docstring)."""
    emotions = list(people.emotions)
    if len(emotions) < 2:
        raise ConfigError(f"emotion tests need >= 2 emotions; the study has {emotions}")
    cube, ids = _cube(participant_gene_means(people), people.genes, emotions)
    if len(ids) < 3:
        raise ConfigError(
            f"emotion tests need >= 3 participants with every emotion; got {len(ids)}"
        )
    pairs = list(itertools.combinations(range(len(emotions)), 2))
    d = np.stack([cube[:, a] - cube[:, b] for a, b in pairs], axis=1)  # (n, C, G)
    res = paired_signflip(d, permutations=opts.permutations, rng=rng)
    lo, hi, method = paired_difference_ci(d, opts, rng=rng)
    used = (cube > USED).mean(axis=0)  # (E, G)
    rows = []
    for c, (a, b) in enumerate(pairs):
        for k, gene in enumerate(people.genes):
            rows.append(
                {
                    "gene": gene_base(gene),
                    "facs_code": facs_code(gene),
                    "contrast": f"{emotions[a]} − {emotions[b]}",
                    "emotion_a": emotions[a],
                    "emotion_b": emotions[b],
                    "n_participants": len(ids),
                    "mean_a": cube[:, a, k].mean(),
                    "mean_b": cube[:, b, k].mean(),
                    "difference": d[:, c, k].mean(),
                    "ci_low": lo[c, k],
                    "ci_high": hi[c, k],
                    "ci_method": method[c, k],
                    "used_a": used[a, k],
                    "used_b": used[b, k],
                    **_stats(res, c, k),
                }
            )
    return _typed(pd.DataFrame(rows), res, 1 - opts.level)


def _stats(res: PermutationResult, c: int, k: int) -> dict[str, float]:
    return {
        "t": float(res.t[c, k]),
        "p_perm": float(res.p[c, k]),
        "p_maxt": float(res.p_maxt[c, k]),
        "q_bh": float(res.q_bh[c, k]),
    }


def _typed(table: pd.DataFrame, res: PermutationResult, alpha: float) -> pd.DataFrame:
    table["significant_maxt"] = table["p_maxt"] < alpha
    table["significant_bh"] = table["q_bh"] < alpha
    table["permutations"] = res.permutations
    table["exact"] = res.exact
    return table


def group_gene_tests(
    people: People, opts: GeneTestOptions, *, rng: np.random.Generator, column: str = "group"
) -> pd.DataFrame:
    """Every gene × emotion × pair of levels of participant column ``column``, between
    participants (see the module docstring)."""
    if column not in people.faces.columns:
        raise ConfigError(f"no participant column '{column}' (join a participant table)")
    emotions = list(people.emotions)
    means = participant_gene_means(people)
    groups = people.faces.groupby("participant_id")[column].first()
    cube, ids = _cube(means, people.genes, emotions)
    found = groups.reindex(ids)
    keep = found.notna().to_numpy()
    cube, label = cube[keep], found[keep].astype(str).to_numpy()
    levels = sorted(set(label))
    if len(levels) < 2:
        raise ConfigError(f"column '{column}' has {len(levels)} level(s) with data; need >= 2")
    pairs = list(itertools.combinations(levels, 2))
    tables = []
    for ga, gb in pairs:
        sub = np.isin(label, [ga, gb])
        x, member = cube[sub], label[sub] == ga
        if member.sum() < 2 or (~member).sum() < 2:
            raise ConfigError(f"groups '{ga}' and '{gb}' need >= 2 participants each")
        res = group_permutation(x, member, permutations=opts.permutations, rng=rng)
        ci = group_difference_ci(x, member, opts, rng=rng)
        tables.append(_group_rows(people, emotions, x, member, (ga, gb), res, ci))
        if len(pairs) > 1:  # Bonferroni over the pairs of groups
            t = tables[-1]
            t["p_maxt"] = np.minimum(1.0, t["p_maxt"] * len(pairs))
        tables[-1] = _typed(tables[-1], res, 1 - opts.level)
    return pd.concat(tables, ignore_index=True)


def paired_difference_ci(
    d: np.ndarray, opts: GeneTestOptions, *, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per contrast × gene: the sign-flip-inverted interval of the mean paired difference
    (:func:`emogen.analysis.permutation.signflip_interval`), and where there are too few
    participants for a finite one (5 at 95%: 32 flips) Student's t interval; and which."""
    lo, hi = signflip_interval(d, level=opts.level, permutations=opts.permutations, rng=rng)
    finite = np.isfinite(lo) & np.isfinite(hi)
    if finite.all():
        return lo, hi, np.full(lo.shape, "sign-flip")
    t_lo, t_hi = t_mean_ci(d, level=opts.level)
    method = np.where(finite, "sign-flip", "Student t (too few participants)")
    return np.where(finite, lo, t_lo), np.where(finite, hi, t_hi), method


def group_difference_ci(
    x: np.ndarray, member: np.ndarray, opts: GeneTestOptions, *, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per emotion × gene: the permutation-inverted interval of the groups' mean difference
    (:func:`emogen.analysis.permutation.shift_interval`), and where the groups are too small for
    a finite one (3 + 3 at 95%: 20 relabellings) Welch's t interval; and which was used."""
    lo, hi = shift_interval(x, member, level=opts.level, permutations=opts.permutations, rng=rng)
    finite = np.isfinite(lo) & np.isfinite(hi)
    if finite.all():
        return lo, hi, np.full(lo.shape, "permutation")
    w_lo, w_hi = welch_difference_ci(x, member, level=opts.level)
    method = np.where(finite, "permutation", "Welch t (too few relabellings)")
    return np.where(finite, lo, w_lo), np.where(finite, hi, w_hi), method


def _group_rows(
    people: People,
    emotions: list[str],
    x: np.ndarray,
    member: np.ndarray,
    names: tuple[str, str],
    res: PermutationResult,
    ci: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> pd.DataFrame:
    a, b = x[member], x[~member]
    rows = []
    for e, emotion in enumerate(emotions):
        for k, gene in enumerate(people.genes):
            rows.append(
                {
                    "gene": gene_base(gene),
                    "facs_code": facs_code(gene),
                    "emotion": emotion,
                    "group_a": names[0],
                    "group_b": names[1],
                    "n_a": len(a),
                    "n_b": len(b),
                    "mean_a": a[:, e, k].mean(),
                    "mean_b": b[:, e, k].mean(),
                    "difference": a[:, e, k].mean() - b[:, e, k].mean(),
                    "ci_low": ci[0][e, k],
                    "ci_high": ci[1][e, k],
                    "ci_method": ci[2][e, k],
                    "used_a": (a[:, e, k] > USED).mean(),
                    "used_b": (b[:, e, k] > USED).mean(),
                    **_stats(res, e, k),
                }
            )
    return pd.DataFrame(rows)
