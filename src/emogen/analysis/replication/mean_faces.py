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
  (the paper's "local error"), against ``sign``;
* ``between`` — vertex RMS (cm) between mean(a) and mean(b) over the smaller of their RMS to
  the target ("nearly identical" relative to how far both are from the target), rule ``band``
  against ``level`` and ``weaker``.

:class:`LineFit` decides on the intensity line of one condition's mean face (Fig. 18).

``arrays``: (faces a (runs × S), faces b (runs × S), the target repeated per run (runs × S)).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from emogen.analysis.replication.geometry import FaceGeometry
from emogen.analysis.replication.intervals import Decision
from emogen.analysis.replication.verdicts import band_verdict, ci_verdict

KINDS = ("rms", "rms_below", "ratio_gap", "ratio", "jaw", "between")


@dataclass(frozen=True)
class MeanFaceTest:
    """A statistic of the mean final faces with a bootstrap 95% interval (see the module)."""

    kind: str
    sign: int = +1
    level: float = 0.0
    seed: int = 0
    resamples: int = 200
    geometry: FaceGeometry | None = field(default=None, compare=False)
    weaker: float = 0.0
    #: the smallest effect of interest of the comparisons (rule ``ci``): 0.05 cm for vertex
    #: distances (rms, jaw: half a millimetre), 0.05 for the nose/jaw ratio
    sesoi: float = 0.05

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
        if self.kind == "between":
            near = [min(g.rms_cm(x, t), g.rms_cm(y, t)) for x, y in zip(a, b, strict=True)]
            return np.array([g.rms_cm(x, y) for x, y in zip(a, b, strict=True)]) / near
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
        target = _one_target(targets)
        counts = _weights(n, self.resamples, self.seed)
        est = float(self._stat(a.mean(0)[None], b.mean(0)[None], target)[0])
        boot = self._stat(counts @ a, counts @ b, target)
        lo, hi = (float(q) for q in np.quantile(boot, [0.025, 0.975]))

        def rule(lo: float, hi: float) -> str:
            if self.kind == "rms_below":
                return band_verdict(lo, hi, self.level, self.level)
            if self.kind == "between":
                return band_verdict(lo, hi, self.level, self.weaker)
            return ci_verdict(lo, hi, self.sign, self.sesoi)

        said = f"bootstrap of the mean faces over runs ({self.kind}), n = {n}"
        if self.kind not in ("rms_below", "between"):
            said += f", SESOI {self.sesoi:g}"
        return Decision(rule(lo, hi), est, lo, hi, 0.95, said, rule)


def _one_target(targets: np.ndarray) -> np.ndarray:
    if np.ptp(targets, axis=0).max() > 0:
        raise ValueError("a mean-face test needs one target for every run")
    return np.asarray(targets[0])


def _weights(n: int, resamples: int, seed: int) -> np.ndarray:
    """Bootstrap weights over n runs (resamples × n), each row summing to 1: the rows times
    the runs' faces are the resampled mean faces."""
    idx = np.random.default_rng(seed).integers(n, size=(resamples, n))
    return np.stack([np.bincount(i, minlength=n) for i in idx]) / n


LINE_KINDS = ("residual", "scale")


@dataclass(frozen=True)
class LineFit:
    """Fig. 18: where one condition's mean final face lies against the target's intensity
    line (:meth:`FaceGeometry.intensity_fits`), bootstrapped over runs (95% percentile
    interval). ``arrays``: (faces (runs × S), the target repeated per run (runs × S)).

    * ``residual`` — the share of the mean face's displacement off the line (the sine of its
      angle to the target's displacement: 0 exactly a scaled target, 1 at right angles), rule
      ``band``: **holds** below ``level``, **differs** when the interval lies at or above it;
    * ``scale`` — the intensity s* of the mean face along the line against the range
      [``level``, ``upper``]: **holds** when the interval lies inside it, **differs** when it
      lies wholly outside, **inconclusive** otherwise."""

    kind: str
    level: float
    upper: float = 0.0
    seed: int = 0
    resamples: int = 200
    geometry: FaceGeometry | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in LINE_KINDS:
            raise ValueError(f"kind must be one of {LINE_KINDS}; got {self.kind!r}")
        if self.kind == "scale" and not self.level < self.upper:
            raise ValueError(f"a scale range needs level < upper; got {self.level}, {self.upper}")

    def __call__(self, *arrays: np.ndarray) -> Decision:
        if len(arrays) != 2:
            raise ValueError("a line fit needs the faces and the target, runs × S")
        faces, targets = (np.asarray(x, dtype=np.float64) for x in arrays)
        if faces.ndim != 2 or targets.shape != faces.shape:
            raise ValueError("a line fit needs the faces and the target, runs × S")
        if self.geometry is None:
            raise ValueError("a line fit needs the face geometry")
        target = _one_target(targets)
        means = np.vstack([faces.mean(0), _weights(len(faces), self.resamples, self.seed) @ faces])
        scale, residual = self.geometry.intensity_fits(means, target)
        stat = residual if self.kind == "residual" else scale
        lo, hi = (float(q) for q in np.quantile(stat[1:], [0.025, 0.975]))
        if self.kind == "residual":
            verdict = band_verdict(lo, hi, self.level, self.level)
        elif self.level <= lo and hi <= self.upper:
            verdict = "holds"
        else:
            verdict = "differs" if hi < self.level or lo > self.upper else "inconclusive"
        said = f"bootstrap of the mean face over runs ({self.kind}), n = {len(faces)}"
        return Decision(verdict, float(stat[0]), lo, hi, 0.95, said)
