"""Verdicts from intervals: the per-run data a finding rests on, pooled over the seeds, and the
test that decides its verdict on them.

A seed's :class:`Evidence` holds per-run arrays (runs in the same order in every array of a
seed: conditions share the seed's per-run generators, so two conditions' runs pair up, common
random numbers). Over seeds the runs are pooled by concatenating each array, and the verdict is
the test's on the pooled runs; each seed's own verdict is kept as a robustness column.

The tests (scipy's; the verdict rules they feed are
:mod:`~emogen.analysis.replication.verdicts`):

* :class:`Direction` — a difference with a direction: the 95% t-interval of the mean paired
  difference (or Welch's, unpaired), rule ``ci``;
* :class:`Equivalence` — "no difference": two one-sided t-tests (TOST) against ±margin, the
  90% interval shown, rule ``tost``;
* :class:`NotWorse` — "not worse than": one-sided, the 90% interval's upper end against the
  margin, rule ``noninferior``;
* :class:`Share` — a share of runs past a level: the Wilson 95% interval, rule ``level``;
* :class:`Number` — our mean against a value the paper gives (μ ± σ): the 95% t-interval,
  rule ``number``.

Margins are stated in the data's own unit or as a share of the pooled SD (``margin_sd``: 0.2 is
Cohen's "small"); a margin from the pooled SD is computed on the pooled runs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np
from scipy import stats

from emogen.analysis.replication.findings import Finding
from emogen.analysis.replication.verdicts import (
    ALPHA,
    ci_verdict,
    join,
    level_verdict,
    noninferior_verdict,
    number_verdict,
    tost_verdict,
)


@dataclass(frozen=True)
class Decision:
    """A test's verdict and what it rests on: the estimate, its interval (``level``: 0.95 or
    0.90) and the test in words."""

    verdict: str
    estimate: float
    lo: float
    hi: float
    level: float
    test: str
    #: the rule with this decision's margins, as a function of an interval: what
    #: :meth:`Evidence.seed_level` applies to the seeds' interval
    rule: Callable[[float, float], str] | None = field(default=None, compare=False)

    def text(self) -> str:
        return (
            f"{self.estimate:+.3g} ({self.level:.0%} CI {self.lo:+.3g}…{self.hi:+.3g}; {self.test})"
        )


class Test(Protocol):
    def __call__(self, *arrays: np.ndarray) -> Decision: ...


def _as(x: np.ndarray) -> np.ndarray:
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 1 or len(a) < 2 or not np.all(np.isfinite(a)):
        raise ValueError(f"per-run data must be ≥ 2 finite values in one dimension; got {a!r}")
    return a


def _pair(a: np.ndarray, b: np.ndarray, paired: bool) -> tuple[np.ndarray, np.ndarray]:
    a, b = _as(a), _as(b)
    if paired and len(a) != len(b):
        raise ValueError(f"paired runs must match in number; got {len(a)} and {len(b)}")
    return a, b


def _interval(a: np.ndarray, b: np.ndarray, paired: bool, level: float) -> tuple[float, float]:
    """The t-interval of mean(a) − mean(b): paired, or Welch's."""
    res = stats.ttest_1samp(a - b, 0.0) if paired else stats.ttest_ind(a, b, equal_var=False)
    ci = res.confidence_interval(level)
    lo, hi = float(ci.low), float(ci.high)
    if not (np.isfinite(lo) and np.isfinite(hi)):  # no spread at all: the interval is the point
        d = float(a.mean() - b.mean())
        return d, d
    return lo, hi


def _margin(a: np.ndarray, b: np.ndarray, margin: float, margin_sd: float) -> float:
    if margin_sd > 0:
        pooled = float(np.sqrt((a.var(ddof=1) + b.var(ddof=1)) / 2))
        return margin_sd * pooled
    return margin


def _margined(
    arrays: tuple[np.ndarray, ...], margin: float, margin_sd: float, paired: bool
) -> tuple[np.ndarray, np.ndarray, float, float, float]:
    """(a, b, the margin, the 90% interval of mean(a) − mean(b)): one-sided α = 0.05 each way."""
    a, b = _pair(arrays[0], arrays[1], paired)
    lo, hi = _interval(a, b, paired, 1 - 2 * ALPHA)
    return a, b, _margin(a, b, margin, margin_sd), lo, hi


def _kind(paired: bool) -> str:
    return "paired t" if paired else "Welch t"


def _ci_rule(sign: int, sesoi: float) -> Callable[[float, float], str]:
    return lambda lo, hi: ci_verdict(lo, hi, sign, sesoi)


@dataclass(frozen=True)
class Direction:
    """mean(a) − mean(b) against the paper's sign (±1): rule ``ci`` on the 95% interval,
    with the smallest effect of interest ``sesoi`` (the data's unit) or ``sesoi_sd`` × the
    pooled SD (default 0.2, Cohen's 'small')."""

    sign: int
    paired: bool = True
    sesoi: float = 0.0
    sesoi_sd: float = 0.2

    def __call__(self, *arrays: np.ndarray) -> Decision:
        a, b = _pair(arrays[0], arrays[1], self.paired)
        lo, hi = _interval(a, b, self.paired, 0.95)
        delta = self.sesoi or _margin(a, b, 0.0, self.sesoi_sd)
        if not delta > 0:  # both arrays constant: any difference at all is of interest
            delta = float(np.finfo(np.float64).eps)
        rule = _ci_rule(self.sign, delta)
        return Decision(
            rule(lo, hi),
            float(a.mean() - b.mean()),
            lo,
            hi,
            0.95,
            f"{_kind(self.paired)}, n = {len(a)}, SESOI {delta:.3g}",
            rule,
        )


def tost_p(a: np.ndarray, b: np.ndarray, margin: float, paired: bool) -> float:
    """TOST p-value of |mean(a) − mean(b)| < margin: the larger of the two one-sided t-tests
    (H0: δ ≤ −margin, H0: δ ≥ +margin), each shifted by the margin."""
    if paired:
        d = a - b
        lower = stats.ttest_1samp(d, -margin, alternative="greater").pvalue
        upper = stats.ttest_1samp(d, margin, alternative="less").pvalue
    else:
        lower = stats.ttest_ind(a + margin, b, equal_var=False, alternative="greater").pvalue
        upper = stats.ttest_ind(a - margin, b, equal_var=False, alternative="less").pvalue
    return float(max(lower, upper))


@dataclass(frozen=True)
class Equivalence:
    """No difference within ±margin (``margin``, or ``margin_sd`` × the pooled SD): TOST at
    α = 0.05, rule ``tost`` on the 90% interval."""

    margin: float = 0.0
    margin_sd: float = 0.0
    paired: bool = True

    def __call__(self, *arrays: np.ndarray) -> Decision:
        a, b, m, lo, hi = _margined(arrays, self.margin, self.margin_sd, self.paired)
        if not m > 0:
            raise ValueError(f"an equivalence margin must be > 0; got {m!r}")
        p = tost_p(a, b, m, self.paired)
        said = f"TOST ±{m:.3g}, p = {p:.2g}, {_kind(self.paired)}, n = {len(a)}"

        def rule(lo: float, hi: float) -> str:  # the 90% interval inside ±m: TOST at α
            return "holds" if -m < lo and hi < m else tost_verdict(1.0, lo, hi, m)

        d = float(a.mean() - b.mean())
        return Decision(tost_verdict(p, lo, hi, m), d, lo, hi, 0.9, said, rule)


@dataclass(frozen=True)
class NotWorse:
    """mean(a) − mean(b) < margin (``a`` not worse than ``b``, lower is better): rule
    ``noninferior`` on the 90% interval (one-sided α = 0.05)."""

    margin: float = 0.0
    margin_sd: float = 0.0
    paired: bool = True

    def __call__(self, *arrays: np.ndarray) -> Decision:
        a, b, m, lo, hi = _margined(arrays, self.margin, self.margin_sd, self.paired)
        said = f"not worse by {m:.3g}, {_kind(self.paired)}, n = {len(a)}"

        def rule(lo: float, hi: float) -> str:
            return noninferior_verdict(lo, hi, m)

        return Decision(rule(lo, hi), float(a.mean() - b.mean()), lo, hi, 0.9, said, rule)


@dataclass(frozen=True)
class SpreadDirection:
    """sd(a) − sd(b) against the paper's sign (±1): rule ``ci`` on a 95% paired bootstrap
    interval (scipy's BCa, ``resamples`` draws from a generator seeded with ``seed``), with
    the smallest effect of interest ``sesoi_rel`` × the mean of the two SDs (default 10%)."""

    sign: int
    seed: int = 0
    resamples: int = 999
    sesoi_rel: float = 0.1

    def __call__(self, *arrays: np.ndarray) -> Decision:
        a, b = _pair(arrays[0], arrays[1], True)

        def diff(x: np.ndarray, y: np.ndarray, axis: int = -1) -> np.ndarray:
            return np.asarray(np.std(x, ddof=1, axis=axis) - np.std(y, ddof=1, axis=axis))

        ci = stats.bootstrap(
            (a, b),
            diff,
            paired=True,
            n_resamples=self.resamples,
            rng=np.random.default_rng(self.seed),
        ).confidence_interval
        lo, hi = float(ci.low), float(ci.high)
        delta = self.sesoi_rel * float(np.mean([a.std(ddof=1), b.std(ddof=1)]))
        rule = _ci_rule(self.sign, max(delta, float(np.finfo(np.float64).eps)))
        return Decision(
            rule(lo, hi),
            float(diff(a, b)),
            lo,
            hi,
            0.95,
            f"paired bootstrap of the SD difference, n = {len(a)}, SESOI {delta:.3g}",
            rule,
        )


@dataclass(frozen=True)
class Share:
    """The share of runs that pass (a 0/1 array) against ``level`` (holds past it) and
    ``weaker`` (partly past it): the Wilson 95% interval, rule ``level``."""

    level: float
    weaker: float

    def __call__(self, *arrays: np.ndarray) -> Decision:
        x = np.asarray(arrays[0])
        if x.ndim != 1 or len(x) == 0 or not np.isin(x, (0, 1)).all():
            raise ValueError(f"a share needs a non-empty 0/1 array; got {x!r}")
        k = int(x.sum())
        ci = stats.binomtest(k, len(x)).proportion_ci(0.95, method="wilson")

        def rule(lo: float, hi: float) -> str:
            return level_verdict(lo, hi, self.level, self.weaker)

        lo, hi = float(ci.low), float(ci.high)
        return Decision(rule(lo, hi), k / len(x), lo, hi, 0.95, f"Wilson, {k} of {len(x)}", rule)


@dataclass(frozen=True)
class Number:
    """Our μ against the paper's ``paper_mu`` ± ``paper_sd``, rule ``number`` on the 95%
    t-interval of our mean. ``arrays``: one or more per-run arrays whose runs pair up (several
    targets averaged the paper's way: a run's value is the mean of its targets' values, σ the
    mean of the targets' SDs)."""

    paper_mu: float
    paper_sd: float

    def __call__(self, *arrays: np.ndarray) -> Decision:
        xs = [_as(a) for a in arrays]
        if len({len(x) for x in xs}) != 1:
            raise ValueError(f"paired runs must match in number; got {[len(x) for x in xs]}")
        per_run = np.mean(xs, axis=0)
        sd = float(np.mean([x.std(ddof=1) for x in xs]))
        ci = stats.ttest_1samp(per_run, self.paper_mu).confidence_interval(0.95)
        lo, hi = float(ci.low), float(ci.high)
        said = f"t over runs, n = {len(per_run)}; σ {sd:.3g} against the paper's {self.paper_sd}"

        def rule(lo: float, hi: float) -> str:
            return number_verdict(lo, hi, sd, self.paper_mu, self.paper_sd)

        return Decision(rule(lo, hi), float(per_run.mean()), lo, hi, 0.95, said, rule)


@dataclass(frozen=True, eq=False)
class Evidence:
    """One seed's per-run arrays and the test deciding on them; :meth:`pool` concatenates
    the seeds' runs array by array."""

    test: Test
    arrays: tuple[np.ndarray, ...]

    def decide(self) -> Decision:
        return self.test(*self.arrays)

    @staticmethod
    def pool(items: list[Evidence]) -> Evidence:
        first = items[0]
        if any(e.test != first.test or len(e.arrays) != len(first.arrays) for e in items):
            raise ValueError("the seeds' evidence must use one test on the same arrays")
        arrays = tuple(
            np.concatenate([e.arrays[i] for e in items]) for i in range(len(first.arrays))
        )
        return Evidence(first.test, arrays)

    @staticmethod
    def seed_level(items: list[Evidence], fitted: str) -> Decision:
        """The decision at the level of a fitted object (rule 'seed level'): each seed's
        estimate (its own fit of ``fitted``), their t-interval over the seeds at the test's
        level, judged by the test's rule with the margins of the pooled runs. One seed has
        no such interval: its runs decide, and the text says so."""
        pooled = Evidence.pool(items).decide()
        x = np.array([e.decide().estimate for e in items], dtype=np.float64)
        x = x[np.isfinite(x)]
        if len(x) < 2 or pooled.rule is None:
            why = "fewer than 2 seeds" if len(x) < 2 else "the test has no seed-level rule"
            if len(items) > 1 and pooled.rule is None:
                raise ValueError(f"{pooled.test}: {why}, yet the quantity rests on {fitted}")
            return replace(pooled, test=f"{pooled.test}; runs pooled: {why}")
        half = float(stats.t.ppf(0.5 + pooled.level / 2, len(x) - 1) * x.std(ddof=1))
        half /= np.sqrt(len(x))
        mean = float(x.mean())
        said = (
            f"t over {len(x)} seeds' estimates, each its own {fitted}; pooled runs: {pooled.test}"
        )
        return Decision(
            pooled.rule(mean - half, mean + half),
            mean,
            mean - half,
            mean + half,
            pooled.level,
            said,
            pooled.rule,
        )


def decided(
    evidence: tuple[Evidence, ...], parts: Callable[[list[str]], str] | None = None
) -> tuple[str, str]:
    """One seed's verdict on its own runs (the parts joined by ``parts``, default
    :func:`~emogen.analysis.replication.verdicts.join`) and the decisions in words."""
    decisions = [e.decide() for e in evidence]
    verdict = (parts or join)([d.verdict for d in decisions])
    return verdict, "; ".join(d.text() for d in decisions)


def judged(
    section: str,
    claim: str,
    paper: str,
    ours: str,
    evidence: list[Evidence],
    rule: str,
    *,
    note: str = "",
    parts: Callable[[list[str]], str] | None = None,
    value: float | None = None,
    value_label: str = "",
    fitted: str = "",
    outside: str = "",
) -> Finding:
    """A finding whose verdict is its evidence's (this seed's runs; over seeds the pooled
    runs'); its effect size defaults to the first part's estimate."""
    ev = tuple(evidence)
    verdict, text = decided(ev, parts)
    if value is None:
        first = ev[0].decide()
        value, value_label = first.estimate, value_label or "first part's estimate"
    return Finding(
        section,
        claim,
        paper,
        ours,
        verdict,
        note,
        rule=rule,
        value=value,
        value_label=value_label,
        evidence=ev,
        parts=parts,
        interval=text,
        fitted=fitted,
        outside=outside,
    )
