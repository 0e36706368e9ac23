"""Figs. 15 and 17 on the pooled runs: rises of KL(P_g ‖ P_g−1) above the KL noise floor.

A seed's evidence is its runs' errors (runs × G + 1); over seeds the runs are pooled, the KL
curve recomputed on all of them and the floor too — the KL two same-size samples of the final
generation's distribution reach by chance (95th percentile,
:func:`~emogen.analysis.distributions.kl_noise_floor`, drawn from a generator seeded with the
test's ``seed``). More runs lower the floor, so a real rise is easier to see pooled than in any
one seed. The count of rises above the floor carries a bootstrap 95% interval over runs (40
resamples: the curve recomputed on resampled runs, the floor held), shown beside the verdict.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.analysis.distributions import kl_noise_floor, kl_per_generation
from emogen.analysis.replication.intervals import Decision

WINDOWS = ("all", "late")


def rises_above(kl: np.ndarray, floor: float, window: str) -> int:
    """Steps of the KL curve (g ≥ 2) up by more than ``floor``; ``late``: in the second half
    of the generations only."""
    if window not in WINDOWS:
        raise ValueError(f"window must be one of {WINDOWS}; got {window!r}")
    curve = kl[len(kl) // 2 - 1 :] if window == "late" else kl
    return int(np.sum(np.diff(curve) > floor))


@dataclass(frozen=True)
class KLRises:
    """The paper's pattern for one condition: ``expect`` a rise (**holds** when the pooled
    curve rises above the floor at least once in ``window``, else **differs**) or none
    (**holds** when it never does, else **differs**)."""

    expect: bool
    window: str = "all"
    seed: int = 0
    resamples: int = 100  # pairs of samples for the floor; the interval takes 40 resamples

    def __post_init__(self) -> None:
        if self.window not in WINDOWS:
            raise ValueError(f"window must be one of {WINDOWS}; got {self.window!r}")

    def __call__(self, *arrays: np.ndarray) -> Decision:
        errors = np.asarray(arrays[0], dtype=np.float64)
        if errors.ndim != 2 or errors.shape[1] < 4 or len(errors) < 2:
            raise ValueError(f"KL rises need errors (runs × ≥ 4 generations); got {errors.shape}")
        rng = np.random.default_rng(self.seed)
        floor = kl_noise_floor(errors[:, -1], len(errors), rng=rng, resamples=self.resamples)
        count = rises_above(kl_per_generation(errors), floor, self.window)
        n = len(errors)
        boot = [
            rises_above(kl_per_generation(errors[rng.integers(n, size=n)]), floor, self.window)
            for _ in range(40)
        ]
        lo, hi = (float(q) for q in np.quantile(boot, [0.025, 0.975]))
        verdict = "holds" if (count > 0) == self.expect else "differs"
        said = f"{self.window} rises above the pooled floor {floor:.4f} nats, n = {n}"
        return Decision(verdict, float(count), lo, hi, 0.95, said)
