"""Coverage of the per-gene and ICC intervals on planted data (the generating process of
``benchmarks/planted_study.py``: sparse prototypes over a Beta(1, 12) floor, Student-t (3 df)
individual deviations, uniform face noise, everything clipped to [0, 1] — bounded, skewed,
often at 0, as genes are).

    python benchmarks/coverage_intervals.py                    # 1000 studies per cell
    python benchmarks/coverage_intervals.py --studies 200 --parts genes

* **genes**: two groups of ``--per-group`` participants (3 repetitions each, per-participant
  means); group b's prototype of one emotion shifted on two genes (+0.15, −0.1). The truth of
  each gene's group difference and of each emotion contrast is its expectation under the
  generating process (0 exactly where the two distributions are the same; else the mean over
  200 000 participants per group). Prints the coverage of the 95% intervals ``emogen analyse``
  tables (inverted permutation tests, ``--permutations`` rearrangements: between groups of a
  shift, between emotions sign flips of the paired differences) and of the Welch t, Student t
  and percentile bootstrap intervals they replaced, for null and true genes, with ±2 SE (SE over studies,
  genes of a study being dependent).
* **icc**: 10-dimensional faces, ``--icc-people`` participants × 3 repetitions; ICC 0 (one
  shared prototype), and ICC about 0.3 (individual deviations); truth of the second from a
  4000-participant study; and two Gaussian cells (12 participants × 2 faces, 5 dimensions of
  unequal variance) at ICC 0 and 0.39. Prints the 95% interval's coverage (``icc_interval``: the
  jackknife on Fisher's z) with ±2 SE. ``--seed``: the docs' figures use ``--seed 20261128``,
  a seed not used while choosing the intervals.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from emogen.analysis.permutation import (
    shift_interval,
    signflip_interval,
    t_mean_ci,
    welch_difference_ci,
)
from emogen.analysis.reliability import components, icc_interval

GENES, EMOTIONS, REPS = 10, 2, 3


def prototypes(rng: np.random.Generator) -> np.ndarray:
    """(emotions, genes) sparse prototypes over a Beta(1, 12) floor."""
    pop = rng.beta(1.0, 12.0, size=(EMOTIONS, GENES))
    for e in range(EMOTIONS):
        active = rng.choice(GENES, size=3, replace=False)
        pop[e, active] = rng.uniform(0.4, 0.9, size=3)
    return pop


def participant_means(
    pop: np.ndarray, n: int, rng: np.random.Generator, spread: float = 0.12
) -> np.ndarray:
    """(n, emotions, genes) each participant's mean over REPS clipped faces."""
    own = np.clip(pop[None] + spread * rng.standard_t(3, size=(n, *pop.shape)), 0, 1)
    faces = own[:, None] + rng.uniform(-0.05, 0.05, size=(n, REPS, *pop.shape))
    return np.clip(faces, 0, 1).mean(axis=1)


def percentile_boot(d: np.ndarray, rng: np.random.Generator, draws: int = 1000) -> tuple:
    """The replaced interval: percentile bootstrap of the mean over participants."""
    n = len(d)
    means = np.stack([d[rng.integers(0, n, n)].mean(axis=0) for _ in range(draws)])
    return np.quantile(means, 0.025, axis=0), np.quantile(means, 0.975, axis=0)


def gene_coverage(args: argparse.Namespace, rng: np.random.Generator) -> None:
    pop_a = prototypes(rng)
    pop_b = pop_a.copy()
    pop_b[0, 0] += 0.15
    pop_b[0, 1] = np.clip(pop_b[0, 1] - 0.1, 0, 1)
    shifted = np.zeros((EMOTIONS, GENES), dtype=bool)
    shifted[0, :2] = True
    big = 200_000
    truth_group = np.where(
        shifted,
        participant_means(pop_b, big, rng).mean(0) - participant_means(pop_a, big, rng).mean(0),
        0.0,
    )
    big_a = participant_means(pop_a, big, rng)
    truth_emotion = (big_a[:, 0] - big_a[:, 1]).mean(0)
    hits = {k: [] for k in ("shift", "welch", "boot_group", "flip", "student", "boot_paired")}
    n = args.per_group
    for _ in range(args.studies):
        a, b = participant_means(pop_a, n, rng), participant_means(pop_b, n, rng)
        x, member = np.concatenate([b, a]), np.arange(2 * n) < n
        lo, hi = shift_interval(x, member, level=0.95, permutations=args.permutations, rng=rng)
        hits["shift"].append((lo <= truth_group) & (truth_group <= hi))
        lo, hi = welch_difference_ci(x, member, level=0.95)
        hits["welch"].append((lo <= truth_group) & (truth_group <= hi))
        diffs = np.stack(
            [
                b[rng.integers(0, n, n)].mean(0) - a[rng.integers(0, n, n)].mean(0)
                for _ in range(1000)
            ]
        )
        blo, bhi = np.quantile(diffs, 0.025, axis=0), np.quantile(diffs, 0.975, axis=0)
        hits["boot_group"].append((blo <= truth_group) & (truth_group <= bhi))
        d = a[:, 0] - a[:, 1]
        lo, hi = signflip_interval(d, level=0.95, permutations=args.permutations, rng=rng)
        hits["flip"].append((lo <= truth_emotion) & (truth_emotion <= hi))
        lo, hi = t_mean_ci(d, level=0.95)
        hits["student"].append((lo <= truth_emotion) & (truth_emotion <= hi))
        blo, bhi = percentile_boot(d, rng)
        hits["boot_paired"].append((blo <= truth_emotion) & (truth_emotion <= bhi))
    print(f"\n== per-gene 95% intervals: {args.studies} studies, {n} participants per group")
    for name, label in (
        ("shift", "groups, permutation-inverted (analyse)"),
        ("welch", "groups, Welch t (before)"),
        ("boot_group", "groups, percentile bootstrap (before)"),
    ):
        h = np.array(hits[name])  # (studies, emotions, genes)
        _line(f"{label}, null genes", h[:, ~shifted & (truth_group == 0)])
        _line(f"{label}, true genes", h[:, shifted])
    for name, label in (
        ("flip", "emotions, sign-flip inverted (analyse)"),
        ("student", "emotions, paired Student t (before)"),
        ("boot_paired", "emotions, percentile bootstrap (before)"),
    ):
        _line(f"{label}, all genes", np.array(hits[name]))


def _line(label: str, h: np.ndarray) -> None:
    """Coverage pooled over studies and genes; its SE from the per-study shares."""
    per_study = h.reshape(len(h), -1).mean(axis=1)
    cov, se = per_study.mean(), per_study.std(ddof=1) / np.sqrt(len(per_study))
    ok = "within" if abs(cov - 0.95) <= 2 * se else "OUTSIDE"
    print(f"  {label}: {cov:.3f} ± {2 * se:.3f} (2 SE; {ok} 2 SE of 0.95; {h.size} intervals)")


def icc_coverage(args: argparse.Namespace, rng: np.random.Generator) -> None:
    print(
        f"\n== ICC 95% intervals (jackknife on Fisher z): {args.studies} studies of {args.icc_people} "
        f"participants × {REPS} repetitions, {GENES} dimensions"
    )
    centre = rng.uniform(0.2, 0.8, size=GENES)

    def study(n: int, spread: float) -> tuple[np.ndarray, np.ndarray]:
        own = centre + spread * rng.standard_t(5, size=(n, GENES))
        faces = own[:, None] + rng.uniform(-0.15, 0.15, size=(n, REPS, GENES))
        return np.clip(faces, 0, 1).reshape(n * REPS, GENES), np.repeat(np.arange(n), REPS)

    def gaussian(n: int, spread: float) -> tuple[np.ndarray, np.ndarray]:
        """12 participants × 2 faces, 5 Gaussian dimensions of unequal variance; person effects
        of SD ``spread`` × the face noise's (true ICC spread² / (1 + spread²))."""
        person = spread * rng.normal(size=(12, 1, 5))
        x = (person + rng.normal(size=(12, 2, 5))) * np.array([0.5, 0.8, 1.0, 1.5, 2.0])
        return x.reshape(12 * 2, 5), np.repeat(np.arange(12), 2)

    cells = (
        ("planted, ICC 0", study, 0.0),
        ("planted, individual deviations", study, 0.06),
        ("Gaussian, 12 participants × 2 faces, 5 dimensions", gaussian, 0.0),
        ("Gaussian, 12 participants × 2 faces, 5 dimensions", gaussian, 0.8),
    )
    for label, draw, spread in cells:
        if draw is gaussian:
            truth = spread**2 / (1 + spread**2)
        else:
            truth = 0.0 if spread == 0 else components(*draw(4000, spread)).icc
        covered = []
        for _ in range(args.studies):
            lo, hi = icc_interval(*draw(args.icc_people, spread))
            covered.append(lo <= truth <= hi)
        c = np.mean(covered)
        se = np.sqrt(0.95 * 0.05 / len(covered))
        ok = "within" if abs(c - 0.95) <= 2 * se else "OUTSIDE"
        print(
            f"  {label} (true ICC {truth:.3f}): covered {int(np.sum(covered))} of "
            f"{len(covered)} = {c:.3f} (2 SE of 0.95: ±{2 * se:.3f}; {ok})"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--studies", type=int, default=1000)
    ap.add_argument("--per-group", type=int, default=8)
    ap.add_argument("--permutations", type=int, default=999)
    ap.add_argument("--icc-people", type=int, default=20)
    ap.add_argument("--parts", nargs="+", choices=("genes", "icc"), default=["genes", "icc"])
    ap.add_argument("--seed", type=int, default=4104)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    start = time.perf_counter()
    if "genes" in args.parts:
        gene_coverage(args, rng)
    if "icc" in args.parts:
        icc_coverage(args, rng)
    print(f"\n({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
