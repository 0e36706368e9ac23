"""Intervals for Table III: the first repeatability bin (share of final-face pairs with
CD < 0.25) and the initial bias, bootstrapped over runs, for the paper's two readings of
"protocol repeatability is less sensitive to bias".

* **within initialisation** (the paper's arithmetic): each initialisation's slope — first-bin
  points gained per unit of bias lost from target 1 to the average target — protocol's below
  each fixed set's;
* **matched bias**: rows of different initialisations with similar bias side by side; the
  fixed row piles more pairs into the first bin than protocol initialisation would at the
  fixed row's bias (protocol's share moved along protocol's own slope by the bias gap, so a
  fixed row that is a little closer to the target gains nothing from it).

Runs are resampled with replacement (the same resampled runs in every condition: they share
the runs' seeds), within each seed (``group``): pairs are only formed within a seed, since the
average target is the seed's own. A pair of copies of one run is not a pair. The interval is
the bootstrap percentile 95% interval; the verdict rule ``ci``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.analysis.repeatability import BIN_EDGES
from emogen.analysis.replication.intervals import Decision
from emogen.analysis.replication.verdicts import band_verdict, ci_verdict

FIRST_BIN = BIN_EDGES[1]
KINDS = ("slope", "matched")


def pair_cd(faces: np.ndarray) -> np.ndarray:
    """CD of every pair of faces (runs × runs): 1 with one neutral face, 0 with two."""
    f = np.asarray(faces, dtype=np.float64)
    norms = np.linalg.norm(f, axis=1)
    zero = norms == 0
    unit = np.divide(f, norms[:, None], out=np.zeros_like(f), where=~zero[:, None])
    cd = np.clip(1.0 - unit @ unit.T, 0.0, 2.0)
    return np.where(zero[:, None] | zero[None, :], np.where(zero[:, None] & zero[None], 0, 1), cd)


def close_pairs(faces: np.ndarray, group: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(pairs with CD < 0.25, pairs at all) as 0/1 matrices over runs of one group, diagonal
    included (the quadratic forms below take it out)."""
    same = group[:, None] == group[None, :]
    return ((pair_cd(faces) < FIRST_BIN) & same).astype(np.float64), same.astype(np.float64)


def first_bin_share(close: np.ndarray, same: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Share of close pairs among the pairs of distinct runs, runs weighted by their counts
    ``w`` (resamples × runs)."""
    num = ((w @ close) * w).sum(axis=1) - (w**2) @ np.diag(close)
    den = ((w @ same) * w).sum(axis=1) - (w**2) @ np.diag(same)
    return np.asarray(num / den)


def _counts(group: np.ndarray, resamples: int, rng: np.random.Generator) -> np.ndarray:
    """Bootstrap counts per run (resamples × runs), resampling within each group; the first
    row is the data themselves (every count 1)."""
    w = np.zeros((resamples + 1, len(group)))
    w[0] = 1.0
    for g in np.unique(group):
        idx = np.flatnonzero(group == g)
        w[1:, idx] = rng.multinomial(len(idx), np.full(len(idx), 1 / len(idx)), size=resamples)
    return w


@dataclass(frozen=True)
class BinContrast:
    """A contrast of Table III rows, bootstrapped over runs. ``arrays``: the group (seed) of
    each run, then per row its final faces (runs × S) and initial biases (runs,):

    * ``slope``: rows (protocol target 1, protocol average, fixed target 1, fixed average);
      estimate slope(protocol) − slope(fixed), slope = (share_avg − share_t1) / (bias_t1 −
      bias_avg) in first-bin points per unit bias;
    * ``matched``: rows (protocol target 1, protocol average, the protocol row matched,
      the fixed row matched); estimate share_fixed − (share_protocol + slope(protocol) ×
      (bias_protocol − bias_fixed)), in points.

    ``sign``: the paper's sign of the estimate (``ci`` rule on the 95% interval); ``sesoi``:
    its smallest effect of interest — 5 first-bin points (``matched``), or 25 points per unit
    bias (``slope``: 5 points over a bias change of 0.2, the span of Table III's rows)."""

    kind: str
    sign: int
    seed: int = 0
    resamples: int = 400
    sesoi: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}; got {self.kind!r}")

    def __call__(self, *arrays: np.ndarray) -> Decision:
        group = np.asarray(arrays[0])
        rows = [(arrays[i], np.asarray(arrays[i + 1], float)) for i in range(1, len(arrays), 2)]
        if len(rows) != 4 or any(len(f) != len(group) or len(b) != len(group) for f, b in rows):
            raise ValueError("a Table III contrast needs a group array and 4 rows of runs")
        w = _counts(group, self.resamples, np.random.default_rng(self.seed))
        share, bias = [], []
        for faces, b in rows:
            close, same = close_pairs(faces, group)
            share.append(100 * first_bin_share(close, same, w))
            bias.append(w @ b / w.sum(axis=1))
        slope_p = (share[1] - share[0]) / (bias[0] - bias[1])
        if self.kind == "slope":
            est = slope_p - (share[3] - share[2]) / (bias[2] - bias[3])
        else:
            est = share[3] - (share[2] + slope_p * (bias[2] - bias[3]))
        lo, hi = (float(q) for q in np.quantile(est[1:], [0.025, 0.975]))
        unit = "points per unit bias" if self.kind == "slope" else "first-bin points"
        delta = self.sesoi or (25.0 if self.kind == "slope" else 5.0)
        said = f"bootstrap over runs within seeds, {unit}, n = {len(group)}, SESOI {delta:g}"

        def rule(lo: float, hi: float) -> str:
            return ci_verdict(lo, hi, self.sign, delta)

        return Decision(rule(lo, hi), float(est[0]), lo, hi, 0.95, said, rule)


SHARE_KINDS = ("first_at_least", "first_above", "tvd_below", "tvd_to")


def bin_pairs(faces: np.ndarray, group: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Per repeatability bin, its pairs as a 0/1 matrix over runs of one group (the last bin
    closed and open-ended), and the pairs at all."""
    same = group[:, None] == group[None, :]
    index = np.searchsorted(np.asarray(BIN_EDGES[1:-1]), pair_cd(faces), side="right")
    bins = [((index == k) & same).astype(np.float64) for k in range(len(BIN_EDGES) - 1)]
    return bins, same.astype(np.float64)


@dataclass(frozen=True)
class BinShares:
    """Table III's bins of one or two rows, bootstrapped over runs within seeds (95%
    percentile interval). ``arrays``: the group (seed) of each run, then one or two rows of
    final faces (runs × S):

    * ``first_at_least`` — the first-bin share (points) of the row against ``level``: **holds**
      when the interval lies at or above it, **differs** when below, else **inconclusive**;
    * ``first_above`` — first-bin share of row 1 − row 2 (points), rule ``ci`` with sign +1
      and a smallest effect of interest of 5 points;
    * ``tvd_below`` — the total variation distance of the two rows' bins (points), rule
      ``band``: **holds** when the interval's upper end is below ``level``, **partly** below
      ``weaker``, **differs** when its lower end is at or above ``weaker``, else
      **inconclusive**;
    * ``tvd_to`` — the same between one row's bins and ``reference`` (the paper's row, in
      points)."""

    kind: str
    level: float = 0.0
    weaker: float = 0.0
    seed: int = 0
    resamples: int = 400
    reference: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if self.kind not in SHARE_KINDS:
            raise ValueError(f"kind must be one of {SHARE_KINDS}; got {self.kind!r}")

    def __call__(self, *arrays: np.ndarray) -> Decision:
        group = np.asarray(arrays[0])
        rows = arrays[1:]
        if len(rows) != (1 if self.kind in ("first_at_least", "tvd_to") else 2):
            raise ValueError(f"{self.kind} needs a group array and the rows it compares")
        w = _counts(group, self.resamples, np.random.default_rng(self.seed))
        shares = []
        for faces in rows:
            bins, same = bin_pairs(faces, group)
            shares.append(np.stack([100 * first_bin_share(b, same, w) for b in bins], axis=1))
        if self.kind == "first_at_least":
            est = shares[0][:, 0]
        elif self.kind == "first_above":
            est = shares[0][:, 0] - shares[1][:, 0]
        else:
            other = shares[1] if self.kind == "tvd_below" else self._reference(shares[0])
            est = 0.5 * np.abs(shares[0] - other).sum(axis=1)
        lo, hi = (float(q) for q in np.quantile(est[1:], [0.025, 0.975]))
        said = f"bootstrap over runs within seeds, {self.kind}, points, n = {len(group)}"
        return Decision(self._rule(lo, hi), float(est[0]), lo, hi, 0.95, said, self._rule)

    def _rule(self, lo: float, hi: float) -> str:
        if self.kind == "first_at_least":
            return "holds" if lo >= self.level else "differs" if hi < self.level else "inconclusive"
        if self.kind == "first_above":
            return ci_verdict(lo, hi, +1, 5.0)
        return band_verdict(lo, hi, self.level, self.weaker)

    def _reference(self, shares: np.ndarray) -> np.ndarray:
        ref = np.asarray(self.reference, dtype=np.float64)
        if ref.shape != shares.shape[1:]:
            raise ValueError(f"the reference needs {shares.shape[1]} bins; got {self.reference}")
        return ref
