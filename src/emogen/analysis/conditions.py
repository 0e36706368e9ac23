"""Tests between conditions — emotions, identities and their interaction — with the participant
as the unit: a repeated-measures permutation MANOVA on the genes.

Each participant's final faces are averaged per emotion × identity cell (over repetitions):
Y[i, e, d] is a gene vector. Participants missing a cell are left out (and counted).

* **emotion**: Y averaged over identities, (n, E, genes); **identity**: averaged over emotions,
  (n, D, genes); **emotion × identity**: each cell's deviation from its emotion's mean over
  identities, the D deviations stacked into one vector per participant × emotion (n, E, D·genes)
  — under no interaction that vector is the same identity effect for every emotion.
* The statistic (:func:`within_permutation_test`): each participant's vectors centred on their
  own mean (removes the participant), then the pseudo-F of a one-way repeated-measures design
  with Euclidean distance (McArdle & Anderson 2001; Anderson 2001, PERMANOVA):
  F = [SS_effect / (k − 1)] / [SS_error / ((k − 1)(n − 1))], SS_effect = n · Σ_k ‖mean_i y_ik‖²
  and SS_error the rest of the within-participant sum of squares. Euclidean distance on genes is
  the GA's own gene-space distance; it equals that on all PCA scores (a rotation).
* The p-value: permutations of the condition labels **within each participant** (the
  conditions are exchangeable within a participant under H0; participants are never mixed),
  ``(1 + #{F* ≥ F}) / (1 + B)``; exact enumeration when (k!)^n ≤ B.
* Effect size: partial η² = SS_effect / (SS_effect + SS_error) (the share of the
  within-participant variation the conditions explain; ≈ 1/n under H0 by chance alone), and
  its bootstrap bias-corrected value with a basic bootstrap CI over participants.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.block_positions import order_sentence
from emogen.analysis.people import People
from emogen.analysis.results import Section
from emogen.errors import ConfigError

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

CHUNK = 200


@dataclass(frozen=True)
class ConditionTest:
    """One effect: its pseudo-F, permutation p, partial η² with its CI, and sizes."""

    effect: str
    n_participants: int
    levels: int
    pseudo_f: float
    p_perm: float
    partial_eta2: float
    partial_eta2_corrected: float
    ci_low: float
    ci_high: float
    permutations: int
    exact: bool


def _sums(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """SS_effect and the total within-participant SS of y (..., n, k, G), centred per
    participant already; leading axes are batches."""
    n = y.shape[-3]
    effect = n * (y.mean(axis=-3) ** 2).sum(axis=(-1, -2))
    total = (y**2).sum(axis=(-1, -2, -3))
    return effect, total


def _f(effect: np.ndarray, total: np.ndarray, n: int, k: int) -> np.ndarray:
    error = np.maximum(total - effect, 1e-300)
    return (effect / (k - 1)) / (error / ((k - 1) * (n - 1)))


def within_permutation_test(
    y: np.ndarray, *, permutations: int, rng: np.random.Generator
) -> tuple[float, float, float, int, bool]:
    """Pseudo-F, p, partial η², the number of relabellings and whether exact, for y
    (n participants, k conditions, G outcomes): condition labels permuted within participants."""
    n, k, _ = y.shape
    if n < 2 or k < 2:
        raise ConfigError(
            f"a within-participant test needs >= 2 participants and 2 levels; got {n}, {k}"
        )
    yc = y - y.mean(axis=1, keepdims=True)
    effect, total = _sums(yc)
    f_obs = float(_f(effect, total, n, k))
    eta = float(effect / total) if total > 0 else 0.0
    exact = math.factorial(k) ** n <= permutations
    null: list[np.ndarray] = []
    rows = np.arange(n)[None, :, None]
    if exact:
        orders = np.array(list(itertools.product(itertools.permutations(range(k)), repeat=n)))
        for o in np.array_split(orders, max(1, len(orders) // CHUNK)):
            e, t = _sums(yc[rows, o])
            null.append(_f(e, t, n, k))
    else:
        left = permutations
        while left > 0:
            b = min(CHUNK, left)
            o = rng.random((b, n, k)).argsort(axis=2)
            e, t = _sums(yc[rows, o])
            null.append(_f(e, t, n, k))
            left -= b
    f_null = np.concatenate(null)
    over = int((f_null >= f_obs * (1 - 1e-12)).sum())
    p = over / len(f_null) if exact else (over + 1) / (len(f_null) + 1)
    return f_obs, p, eta, len(f_null), exact


def _eta_ci(
    y: np.ndarray, eta: float, *, level: float, draws: int, rng: np.random.Generator
) -> tuple[float, float, float]:
    """Bootstrap bias-corrected partial η² and its basic (reverse-percentile) bootstrap CI,
    resampling participants (Davison & Hinkley 1997, §5.2): a resample repeats participants,
    which inflates SS_effect, so the resamples sit above η² (by about the noise's share, ~1/n);
    the corrected value 2η² − median(η²*) and the interval [2η² − q_hi, 2η² − q_lo] both move
    down by that bias (clipped at 0)."""
    yc = y - y.mean(axis=1, keepdims=True)
    n = len(yc)
    etas = np.empty(draws)
    for b in range(draws):
        e, t = _sums(yc[rng.integers(0, n, n)])
        etas[b] = float(e / t) if t > 0 else 0.0
    q_lo, q_hi = np.quantile(etas, [(1 - level) / 2, (1 + level) / 2])
    lo, hi = 2 * eta - q_hi, 2 * eta - q_lo
    bias = float(np.median(etas)) - eta
    return max(0.0, eta - bias), max(0.0, float(lo)), max(0.0, float(hi))


def cell_cube(people: People) -> tuple[np.ndarray, list[str], list[str], list[str]]:
    """(n, emotions, identities, genes) cell means of participants with every cell, and the
    participant ids, emotions and identities."""
    f = people.faces
    keys = ["participant_id", "emotion", "identity"]
    means = f.groupby(keys, observed=True)[list(people.genes)].mean()
    emotions, idents = list(people.emotions), list(people.identity_names)
    pids = sorted(f["participant_id"].astype(str).unique())
    means = means.reindex(pd.MultiIndex.from_product([pids, emotions, idents]))
    cube = means.to_numpy(np.float64).reshape(len(pids), len(emotions), len(idents), -1)
    ok = ~np.isnan(cube).any(axis=(1, 2, 3))
    return cube[ok], [i for i, k in zip(pids, ok, strict=True) if k], emotions, idents


def condition_tests(
    people: People,
    *,
    permutations: int,
    bootstrap: int,
    level: float,
    rng: np.random.Generator,
) -> pd.DataFrame:
    """One row per effect the design supports (emotion with >= 2 emotions, identity with >= 2
    identities, their interaction with both): see the module docstring."""
    cube, ids, emotions, idents = cell_cube(people)
    n = len(ids)
    if n < 3:
        raise ConfigError(f"condition tests need >= 3 participants with every cell; got {n}")
    e, d = len(emotions), len(idents)
    effects: list[tuple[str, np.ndarray]] = []
    if e >= 2:
        effects.append(("emotion", cube.mean(axis=2)))
    if d >= 2:
        effects.append(("identity", cube.mean(axis=1)))
    if e >= 2 and d >= 2:
        dev = cube - cube.mean(axis=2, keepdims=True)
        effects.append(("emotion × identity", dev.reshape(n, e, -1)))
    if not effects:
        raise ConfigError("condition tests need >= 2 emotions or >= 2 identities")
    rows = []
    for name, y in effects:
        f, p, eta, b, exact = within_permutation_test(y, permutations=permutations, rng=rng)
        corrected, lo, hi = _eta_ci(y, eta, level=level, draws=bootstrap, rng=rng)
        rows.append(
            ConditionTest(name, n, y.shape[1], f, p, eta, corrected, lo, hi, b, exact).__dict__
        )
    return pd.DataFrame(rows)


def conditions_section(
    people: People, folder: Path, opts: AnalysisOptions, model: FaceModel | None
) -> Section:
    """The tests between emotions, identities and their interaction into the section; headline
    numbers into ``analysis.json``'s ``conditions``."""
    report = Section(folder)
    del model
    report.heading("Emotions, identities and their interaction")
    if len(people.emotions) < 2 and len(people.identity_names) < 2:
        report.paragraph("The study has one emotion and one identity: no condition to compare.")
        return report
    _, ids, _, _ = cell_cube(people)
    if len(ids) < 3:
        report.paragraph(
            f"Condition tests need >= 3 participants with a face in every emotion × identity "
            f"cell; {len(ids)} have one."
        )
        return report
    permutations, draws = 2000, 1000
    table = condition_tests(
        people,
        permutations=permutations,
        bootstrap=draws,
        level=1 - opts.alpha,
        rng=np.random.default_rng(opts.seed),
    )
    left_out = people.n_participants - len(ids)
    report.paragraph(
        "**Unit: the participant.** Test: a repeated-measures permutation MANOVA on the genes "
        "(PERMANOVA-style pseudo-F with Euclidean gene distance, McArdle & Anderson 2001): each "
        "participant's final faces averaged per emotion × identity cell, centred on the "
        "participant's own mean; condition labels permuted **within** participants "
        f"({permutations} permutations, seed {opts.seed}). The interaction tests whether the "
        "identity difference is the same for every emotion (each cell's deviation from its "
        "emotion's mean over identities, permuted over emotions). Assumes participants "
        "independent and, under H0, the conditions exchangeable within a participant (no order "
        f"effect tied to the condition). {order_sentence(people.trials)} Effect: partial η² "
        "(within-participant sum of squares explained) and its bootstrap bias-corrected value "
        f"with a {1 - opts.alpha:.0%} basic bootstrap CI over participants ({draws} resamples). Not a mixed "
        f"model. {left_out} participant(s) without every cell left out."
    )
    report.table(
        table,
        "conditions_tests",
        "Emotion, identity and interaction effects on the genes (participant as unit).",
    )
    report.data["conditions"] = {}
    for r in table.to_dict("records"):
        record = {"p": r["p_perm"], "partial_eta2": r["partial_eta2"]}
        report.data["conditions"][r["effect"]] = record
        report.add_test(
            f"conditions.{r['effect']}",
            record,
            test="within-participant permutation (pseudo-F)",
            p=r["p_perm"],
            n=r["n_participants"],
            statistic=r["pseudo_f"],
            level=1 - opts.alpha,
            effect=("partial η² (bias-corrected)", r["partial_eta2_corrected"],
                    r["ci_low"], r["ci_high"]),
        )  # fmt: skip
    return report
