"""An empirical null for the spread test: a participant's repeated faces of one emotion.

Where each participant made the same emotion (on the same identity) several times, the spread
of their own repeated faces *is* the GA noise plus their choice noise, measured on the people
themselves — no simulated GA, no assumed choice noise T. Different targets across people show
as faces of different participants lying further apart than faces of one participant:

* within = mean CD between two faces of one participant; between = mean CD between faces of
  two different participants; their ratio between / within (1 under the null);
* the **excess between-person spread** σ²_b in CD units: the one-way random-effects variance
  between participants of the faces as unit vectors (‖u − v‖² = 2 CD, so E CD_between −
  E CD_within = σ²_b), estimated as in :mod:`emogen.analysis.reliability` (method of moments,
  any unbalanced design), with the jackknife-t 95% interval over participants (the participant
  is the unit);
* one-sided p: a permutation test of the faces among participants, each keeping their number
  of faces (Anderson 2001's test of a random factor on distances): under the null — no person
  has a target of their own — the faces of a group are exchangeable, so the within-participant
  sum of squares of the data is a draw from its permutation distribution; a between-person
  spread makes it small. p = (1 + #{permuted ≤ observed}) / (1 + permutations).

The test needs at least 2 participants with 2 or more faces; the comparison is within a group
(one emotion, one identity), so no identity or emotion effect enters the within spread. A
neutral face (all weights 0) has no direction: it is left out of the test and counted
(``neutral``), and the minimum applies to the faces that remain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.analysis.reliability import _blocks, _codes, _components, jackknife_interval
from emogen.errors import DataError


@dataclass(frozen=True)
class EmpiricalSpread:
    """Between-participant spread of a group against its within-participant spread."""

    group: str
    participants: int
    repeaters: int  # participants with 2 or more faces
    faces: int
    within: float
    between: float
    excess: float
    excess_lo: float
    excess_hi: float
    icc: float
    p_value: float
    alpha: float
    neutral: int = 0  # neutral faces left out (no direction)

    @property
    def ratio(self) -> float:
        return self.between / self.within if self.within > 0 else float("inf")

    @property
    def exceeds(self) -> bool:
        return self.p_value < self.alpha

    def row(self) -> dict[str, object]:
        return {
            "group": self.group,
            "participants": self.participants,
            "with repeats": self.repeaters,
            "faces": self.faces,
            "neutral faces left out": self.neutral,
            "within-person CD": round(self.within, 4),
            "between-person CD": round(self.between, 4),
            "between / within": round(self.ratio, 3),
            "excess σ²_b [95% CI]": (
                f"{self.excess:+.4f} [{self.excess_lo:+.4f}, {self.excess_hi:+.4f}]"
            ),
            "ICC": round(self.icc, 3),
            "p": float(f"{self.p_value:.3g}"),
            "exceeds within-person noise": self.exceeds,
        }

    def record(self) -> dict[str, object]:
        """The row for machines (``tables/*.csv``): full precision, identifier names."""
        return {
            "group": self.group,
            "participants": self.participants,
            "participants_with_repeats": self.repeaters,
            "faces": self.faces,
            "neutral_faces_left_out": self.neutral,
            "within_cd": self.within,
            "between_cd": self.between,
            "between_within_ratio": self.ratio,
            "excess_between_variance": self.excess,
            "excess_ci_low": self.excess_lo,
            "excess_ci_high": self.excess_hi,
            "icc": self.icc,
            "p": self.p_value,
            "exceeds_within_noise": self.exceeds,
        }


def has_repeats(participants: np.ndarray, faces: np.ndarray | None = None) -> bool:
    """Whether at least 2 participants made 2 or more faces (the test's minimum); with
    ``faces``, counting only those that are not neutral."""
    who = np.asarray(participants).astype(str)
    if faces is not None:
        who = who[_directed(np.asarray(faces, dtype=np.float64))]
    _, counts = np.unique(who, return_counts=True)
    return int((counts >= 2).sum()) >= 2


def _directed(faces: np.ndarray) -> np.ndarray:
    """Which faces (n, S) have a direction (are not neutral)."""
    return np.asarray(np.linalg.norm(faces, axis=1) > 0)


def empirical_spread_test(
    faces: np.ndarray,
    participants: np.ndarray,
    *,
    group: str = "",
    alpha: float = 0.05,
    permutations: int = 999,
    rng: np.random.Generator,
) -> EmpiricalSpread:
    """Does the between-participant spread of ``faces (n_faces, S)`` exceed their
    within-participant spread (see the module)? ``participants``: (n_faces,) whose face."""
    w = np.asarray(faces, dtype=np.float64)
    if w.ndim != 2 or len(w) != len(participants):
        raise DataError(
            f"group '{group}': faces {w.shape} and participants ({len(participants)}) differ"
        )
    if not has_repeats(participants, w):
        raise DataError(
            f"group '{group}': the empirical null needs at least 2 participants with 2 or more "
            "faces each (neutral faces, which have no direction, not counted)"
        )
    keep = _directed(w)
    u = w[keep] / np.linalg.norm(w[keep], axis=1, keepdims=True)  # ‖u − v‖² / 2 = CD
    codes, people = _codes(np.asarray(participants)[keep])
    k, within, p = _blocks(u, codes)
    icc, _, s2b, _ = _components(k, within, p, np.ones(len(people)))[0]
    pairs_within = float(np.sum(k * (k - 1) / 2))
    pairs_between = float((k.sum() ** 2 - np.sum(k**2)) / 2)
    within_cd = float(within.sum() / 2 / pairs_within)
    between_cd = float((p.sum() - np.trace(p)) / 4 / pairs_between)
    lo, hi = jackknife_interval(u, np.asarray(participants)[keep], "between")
    pval = _permutation_p(u, codes, k, permutations, rng)
    return EmpiricalSpread(
        group=group,
        participants=len(people),
        repeaters=int((k >= 2).sum()),
        faces=len(u),
        within=within_cd,
        between=between_cd,
        excess=float(s2b),
        excess_lo=lo,
        excess_hi=hi,
        icc=float(icc),
        p_value=pval,
        alpha=alpha,
        neutral=int((~keep).sum()),
    )


def _permutation_p(
    u: np.ndarray, codes: np.ndarray, k: np.ndarray, permutations: int, rng: np.random.Generator
) -> float:
    """One-sided p of the within-participant sum of squares Σ_i Σ_{j<j′} d² / k_i against its
    distribution over permutations of the faces among participants (counts kept): with the
    counts fixed the total is fixed, so a small within sum is a large between spread."""
    sq = np.sum(u * u, axis=1)
    d2 = np.maximum(sq[:, None] + sq[None, :] - 2 * u @ u.T, 0.0)
    a, b = np.triu_indices(len(u), 1)
    same = codes[a] == codes[b]
    a, b = a[same], b[same]
    weight = 1.0 / k[codes[a]]
    observed = float(np.sum(weight * d2[a, b]))
    count = 0
    for _ in range(permutations):
        perm = rng.permutation(len(u))
        count += int(np.sum(weight * d2[perm[a], perm[b]]) <= observed + 1e-12)
    return (1 + count) / (1 + permutations)
