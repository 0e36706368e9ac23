"""Fig. 9 on intervals: statistics of the mean final face, bootstrapped over runs.

Fig. 9 compares the *mean* final faces of the metrics' observers — a statistic of all runs, not
a per-run value — so its interval is a bootstrap over runs: the same resampled runs in every
condition (the metrics' runs share the runs' seeds, so they pair up), the mean faces recomputed
and the statistic with them; 95% percentile intervals. Over seeds the runs are pooled.

:class:`MeanFaceTest` ``kind``:

* ``rms`` — vertex RMS (cm) of mean(a) to the target minus that of mean(b), against ``sign``;
* ``rms_below`` — vertex RMS (cm) of mean(a) to the target against ``level``: **holds** when
  the interval lies below it, **differs** when above, **inconclusive** across it;
* ``ratio_gap`` — |noseSneer/jawOpen of mean(a) − ``level``| minus the same of mean(b), against
  ``sign`` (which face keeps the target's ratio better);
* ``ratio`` — noseSneer/jawOpen of mean(a) minus that of mean(b), against ``sign``;
* ``jaw`` — the largest vertex distance (cm) of mean(a) from the target minus that of mean(b)
  (the paper's "local error"), against ``sign``.

``arrays``: (faces a (runs × S), faces b (runs × S), the target repeated per run (runs × S)).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from emogen.analysis.replication.geometry import FaceGeometry
from emogen.analysis.replication.intervals import Decision
from emogen.analysis.replication.verdicts import ci_verdict

KINDS = ("rms", "rms_below", "ratio_gap", "ratio", "jaw")


@dataclass(frozen=True)
class MeanFaceTest:
    """A statistic of the mean final faces with a bootstrap 95% interval (see the module)."""

    kind: str
    sign: int = +1
    level: float = 0.0
    seed: int = 0
    resamples: int = 200
    geometry: FaceGeometry | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}; got {self.kind!r}")

    def _stat(self, a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The statistic for mean faces a, b (k × S) and target t (S,): (k,)."""
        g = self.geometry
        if g is None:
            raise ValueError("a mean-face test needs the face geometry")
        if self.kind in ("rms", "rms_below"):
            rms_a = np.array([g.rms_cm(x, t) for x in a])
            return rms_a if self.kind == "rms_below" else rms_a - [g.rms_cm(x, t) for x in b]
        if self.kind == "jaw":
            return np.array([g.max_cm(x, t) - g.max_cm(y, t) for x, y in zip(a, b, strict=True)])

        def ratio(faces: np.ndarray) -> np.ndarray:
            return np.array([g.gene_ratio(x, "noseSneer", over="jawOpen") for x in faces])

        if self.kind == "ratio":
            return ratio(a) - ratio(b)
        return np.abs(ratio(a) - self.level) - np.abs(ratio(b) - self.level)

    def __call__(self, *arrays: np.ndarray) -> Decision:
        a, b, targets = (np.asarray(x, dtype=np.float64) for x in arrays[:3])
        n = len(a)
        if len(arrays) != 3 or a.ndim != 2 or a.shape != b.shape or targets.shape != a.shape:
            raise ValueError("a mean-face test needs faces a, faces b and the target, runs × S")
        if np.ptp(targets, axis=0).max() > 0:
            raise ValueError("a mean-face test needs one target for every run")
        rng = np.random.default_rng(self.seed)
        idx = rng.integers(n, size=(self.resamples, n))
        counts = np.stack([np.bincount(i, minlength=n) for i in idx]) / n
        target = targets[0]
        est = float(self._stat(a.mean(0)[None], b.mean(0)[None], target)[0])
        boot = self._stat(counts @ a, counts @ b, target)
        lo, hi = (float(q) for q in np.quantile(boot, [0.025, 0.975]))
        if self.kind == "rms_below":
            verdict = (
                "holds" if hi < self.level else "differs" if lo > self.level else "inconclusive"
            )
        else:
            verdict = ci_verdict(lo, hi, self.sign)
        said = f"bootstrap of the mean faces over runs ({self.kind}), n = {n}"
        return Decision(verdict, est, lo, hi, 0.95, said)
