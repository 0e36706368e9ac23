"""Fig. 11 tested where it claims something: a target along *low-variance* PCA directions.

The paper explains std_ED(β)'s better convergence for its target 1 by that target lying in a
low-variance mode (component 31 of 46). Our target 1 (an open jaw) does not: the simulated
participants open the jaw often, so it lies in a high-variance mode. Here a target is built
that does. Candidates: for each component in the lower-variance half (variance below the
median component's), either sign, the positive part of the component mapped onto the genes
(left/right averaged; the eye genes left out — gaze is no expression, and the paper's targets
are expressions), scaled to a largest gene weight of 1, genes below ``SMALLEST`` dropped
— a face the GA can reach. The candidate kept has the largest share of its PCA offset
Δβ = β(target) − β(neutral) in the lower-variance half, among those the PCA space captures
(|Δβ| / |α| ≥ ``CAPTURED``: a direction outside the 99% space is seen by neither metric).
The target is built from each seed's own training set, so the pooled runs test the claim for
the class "targets along low-variance directions", not for one face.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from emogen.analysis.replication.findings import Finding, pm
from emogen.analysis.replication.intervals import Direction, Evidence, SpreadDirection, judged
from emogen.analysis.replication.verdicts import join

if TYPE_CHECKING:
    from emogen.analysis.replication.conditions import Condition
    from emogen.metrics import PCASpace
    from emogen.model.rig import Rig

SMALLEST = 0.05  # gene weights below this are dropped from the target
CAPTURED = 0.9  # the share of the target's norm the PCA space must keep
LABEL = "low-variance target"


@dataclass(frozen=True)
class LowVarianceTarget:
    """The target (named gene weights), its full weights (S,), the component it was built on
    (1-based), its share of Δβ² in the lower-variance half, its largest |Δβ| component
    (1-based) and the training variance along it (Δβᵀ diag(σ²) Δβ / |Δβ|²) against the
    median component variance."""

    named: dict[str, float]
    weights: np.ndarray
    component: int
    low_share: float
    key_component: int
    variance: float
    median_variance: float

    def genes(self) -> str:
        return ", ".join(f"{g} {v:.2f}" for g, v in sorted(self.named.items(), key=lambda x: -x[1]))

    def describe(self, k: int) -> str:
        return (
            f"{self.genes()} (built on component {self.component} of {k}; {self.low_share:.0%} of its "
            f"PCA offset in the lower-variance half, largest in component {self.key_component}; "
            f"training variance along it {self.variance:.4f} against the median component's "
            f"{self.median_variance:.4f})"
        )


def _offset_stats(space: PCASpace, w: np.ndarray) -> tuple[float, float, int, float]:
    """(captured share |Δβ| / |α|, low-half share of Δβ², key component, variance along Δβ)."""
    d = w @ space.components.T  # β(w) − β(0)
    low = space.variances < np.median(space.variances)
    total = float((d**2).sum())
    if total <= 0:
        return 0.0, 0.0, 0, 0.0
    return (
        float(np.sqrt(total) / np.linalg.norm(w)),
        float((d[low] ** 2).sum() / total),
        int(np.argmax(np.abs(d))) + 1,
        float((d**2 * space.variances).sum() / total),
    )


def low_variance_target(space: PCASpace, rig: Rig) -> LowVarianceTarget:
    """The candidate of the module docstring with the largest low-variance share."""
    names = rig.gene_names()
    eye = np.array([g.eye for g in rig.genes])
    median = float(np.median(space.variances))
    best: tuple[float, LowVarianceTarget] | None = None
    for j in np.flatnonzero(space.variances < median):
        for sign in (1.0, -1.0):
            genes = np.maximum(rig.contract(sign * space.components[j][None])[0], 0.0)
            genes[eye] = 0.0  # an expression: gaze is no part of one
            if genes.max() <= 0:
                continue
            genes = np.round(genes / genes.max(), 2)
            named = {n: float(v) for n, v in zip(names, genes, strict=True) if v >= SMALLEST}
            w = np.asarray(rig.weights_from_names(named), dtype=np.float64)
            captured, share, key, var = _offset_stats(space, w)
            if captured < CAPTURED or (best is not None and share <= best[0]):
                continue
            best = (share, LowVarianceTarget(named, w, int(j) + 1, share, key, var, median))
    if best is None:
        raise ValueError("no low-variance component gives a target the PCA space captures")
    return best[1]


def low_variance_finding(ed: Condition, std: Condition, target: LowVarianceTarget) -> Finding:
    """Fig. 11's claim on the low-variance target: std_ED(β) converges better than ED(β) —
    lower μ10 and lower σ10, joined by :func:`join`."""
    return judged(
        "Fig. 11",
        "std_ED(β) converges better than ED(β) for a target along low-variance PCA directions",
        "low-variance modes: std_ED better (target 1, component 31 of 46: 0.453 ± 0.279 vs "
        "0.515 ± 0.334)",
        f"std_ED {pm(*std.stats())} vs ED {pm(*ed.stats())}; target {target.genes()} "
        f"({target.low_share:.0%} of its PCA offset in the lower-variance half)",
        [
            Evidence(Direction(+1), (ed.final_errors, std.final_errors)),
            Evidence(SpreadDirection(+1, seed=12), (ed.final_errors, std.final_errors)),
        ],
        "ci, paired per run (the metrics' runs share seeds): μ10(ED) − μ10(std_ED) > 0, "
        "σ10(ED) − σ10(std_ED) > 0 (bootstrap); parts joined (rule join)",
        note="our target, built per seed on the training set's low-variance PCA components "
        "(the paper's own target 1 lies in component 31 of 46; ours does not — see the target "
        "1 finding's note): the test of the paper's explanation",
        parts=join,
        value_label="μ10 ED − std_ED, low-variance target",
        fitted="low-variance target and empirical metrics, built on that seed's training set",
    )
