"""The verdict rules, written down once, and the combination of several seeds' findings.

A finding with :attr:`~emogen.analysis.replication.findings.Finding.evidence` (per-run data and
the test that decides on them, :mod:`~emogen.analysis.replication.intervals`) is decided on
the runs of all seeds pooled, or, when its quantity rests on one fitted object per seed
(``Finding.fitted``: a GMM, a PCA, an empirical metric's training, a target built from the
seed's runs), on the seeds' estimates (one per fit, rule 'seed level'); each seed's own
verdict is kept as a robustness column. Several parts are joined by the one symmetric
:func:`join`. A finding without evidence keeps the seeds'
common verdict, or **inconclusive** when they disagree. The effect size (``Finding.value``)
is reported as the mean over the seeds with a 95% t-interval (mean ± t₀.₉₇₅,ₖ₋₁ · sd / √k).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy import stats

from emogen.analysis.replication.findings import Finding

#: the significance level of every interval and test (95% intervals; 90% for TOST)
ALPHA = 0.05

#: rule name → the rule in words (the report prints this table)
RULES: dict[str, str] = {
    "order": "orderings: **holds** when every ordering the paper states holds; **partly** when "
    "some do (or only the first place); **differs** when none does",
    "ci": "a difference with a direction, against a smallest effect of interest δ (SESOI, "
    "stated per test; default 0.2 pooled SD for means, 10% of the mean SD for SDs, 5 points "
    "for repeatability shares, 0.05 cm for vertex distances, 0.05 for ratios): **holds** when "
    "the 95% CI excludes 0 on the paper's side and reaches past δ; **differs** when it "
    "excludes 0 on the other side and reaches past −δ, or lies wholly within ±δ (no effect "
    "of interest either way, so a precisely zero effect fails the claim); **inconclusive** "
    "otherwise",
    "number": "a value the paper gives (μ ± σ): the 95% CI of our μ, as a distance from the "
    "paper's μ in pooled σ: **holds** when the whole CI lies within 0.5 σ; **partly** within "
    "1 σ; **differs** when it lies wholly beyond 1 σ; **inconclusive** otherwise",
    "direction": "a qualitative claim: **partly** when our direction agrees (the paper's "
    "qualitative magnitude — 'excellent', 'cannot match' — cannot be scored), **differs** "
    "otherwise",
    "threshold": "a stated level: **holds** at or past the level the claim names (given in the "
    "claim); **partly** past its weaker level; **differs** otherwise",
    "tost": "no difference claimed, tested for equivalence (TOST, α = 0.05) against a stated "
    "margin (the SESOI): **holds** when the 90% CI lies inside ±margin; **differs** when it "
    "lies wholly outside; **inconclusive** otherwise",
    "noninferior": "'not worse than' (lower is better): **holds** when the 90% CI's upper end "
    "is below the margin (the SESOI); **differs** when its lower end is above it; "
    "**inconclusive** otherwise",
    "level": "a share against a stated level: **holds** when its 95% CI lies at or past the "
    "level; **partly** when past the weaker level only; **differs** when wholly short of the "
    "weaker level; **inconclusive** otherwise",
    "compromise": "a setting as a compromise of two criteria (lower is better), paired CIs "
    "(rule ci) against each other setting, per target: **differs** when another is "
    "better on both, **holds** when it is better than every other on at least one, "
    "**inconclusive** otherwise; the targets joined (rule join)",
    "chain": "orderings (x₁ > x₂ > …, per group — a target, a generation), each link a paired "
    "95% CI (rule ci; means: t, SDs: bootstrap): the links of a group joined, then the groups "
    "(rule join)",
    "band": "a distance or residual (lower is better) against stated levels: **holds** when "
    "its 95% CI lies below the level; **partly** when below the weaker level only; "
    "**differs** when it lies wholly at or beyond the weaker level; **inconclusive** otherwise",
    "kl": "KL steps: a rise counts only where KL(P_g ‖ P_g−1) grows by more than the KL "
    "noise floor (95th percentile of the KL of two same-size samples of one distribution); "
    "each initialisation's pattern a part (rule join)",
    "join": "a claim of several parts (symmetric: the same whichever way the parts go): "
    "**holds** when every part holds, **differs** when every part differs; **inconclusive** "
    "when some parts are undecided and the decided ones agree (either way); **partly** when "
    "the decided parts disagree",
    "readings": "two readings the paper leaves open (e.g. the GMM's dimension): their common "
    "verdict, else **inconclusive**",
    "seed level": "a quantity that rests on one fitted object per seed (a GMM, a PCA, an "
    "empirical metric's training set, a target built from the seed's own runs) is decided "
    "at the level of that object: the 95% t-interval (90% for TOST and non-inferiority) of "
    "the seeds' estimates, each seed one fit, under the same rule and SESOI; runs pooled "
    "only where every run is an independent replicate",
    "tally": "the tally counts paper findings only, one per event; model-specific absolute "
    "levels, oracle checks (which use what a study cannot know) and findings that restate "
    "another's event are listed apart, outside it",
}


def ci_verdict(lo: float, hi: float, paper_sign: int, sesoi: float) -> str:
    """Rule 'ci': the 95% CI (lo, hi) of our difference against the paper's sign (±1) and
    the smallest effect of interest ``sesoi`` (> 0): an interval wholly within ±sesoi
    **differs** (no effect of interest), one past 0 **holds** or **differs** by its side."""
    if not sesoi > 0:
        raise ValueError(f"a smallest effect of interest must be > 0; got {sesoi!r}")
    if -sesoi < lo and hi < sesoi:
        return "differs"
    if lo > 0:
        return "holds" if paper_sign > 0 else "differs"
    if hi < 0:
        return "differs" if paper_sign > 0 else "holds"
    return "inconclusive"


def tost_verdict(p: float, lo: float, hi: float, margin: float) -> str:
    """Rule 'tost': TOST p-value ``p`` and the 90% CI (lo, hi) against ±``margin``."""
    if not margin > 0:
        raise ValueError(f"an equivalence margin must be > 0; got {margin!r}")
    if p < ALPHA:
        return "holds"
    return "differs" if lo > margin or hi < -margin else "inconclusive"


def noninferior_verdict(lo: float, hi: float, margin: float) -> str:
    """Rule 'noninferior': the 90% CI (lo, hi) of (ours − reference), lower is better."""
    if margin < 0:
        raise ValueError(f"a non-inferiority margin must be ≥ 0; got {margin!r}")
    return "holds" if hi < margin else "differs" if lo > margin else "inconclusive"


def level_verdict(lo: float, hi: float, level: float, weaker: float) -> str:
    """Rule 'level': the 95% CI (lo, hi) of a share against ``level`` and ``weaker``."""
    if not weaker <= level:
        raise ValueError(f"the weaker level must be ≤ the level; got {weaker!r} > {level!r}")
    if lo >= level:
        return "holds"
    if lo >= weaker:
        return "partly"
    return "differs" if hi < weaker else "inconclusive"


def band_verdict(lo: float, hi: float, level: float, weaker: float) -> str:
    """Rule 'band': the 95% CI (lo, hi) of a quantity where lower is better against
    ``level`` and ``weaker`` (≥ ``level``)."""
    if not level <= weaker:
        raise ValueError(f"the weaker level must be ≥ the level; got {weaker!r} < {level!r}")
    if hi < level:
        return "holds"
    if hi < weaker:
        return "partly"
    return "differs" if lo >= weaker else "inconclusive"


def number_verdict(lo: float, hi: float, sd: float, paper_mu: float, paper_sd: float) -> str:
    """Rule 'number': the 95% CI (lo, hi) of our μ, its distance from the paper's μ in pooled
    σ (√((σ² + σ_paper²) / 2)) against 0.5 and 1 (rule 'band')."""
    pooled = float(np.sqrt((sd**2 + paper_sd**2) / 2))
    if not pooled > 0:
        raise ValueError(f"the pooled σ must be > 0; got σ {sd!r} and the paper's {paper_sd!r}")
    near = 0.0 if lo <= paper_mu <= hi else min(abs(lo - paper_mu), abs(hi - paper_mu))
    far = max(abs(lo - paper_mu), abs(hi - paper_mu))
    return band_verdict(near / pooled, far / pooled, 0.5, 1.0)


def mean_ci(values: list[float]) -> tuple[float, float]:
    """(mean, 95% half-width) over seeds (t-interval; half-width NaN for one seed)."""
    v = np.asarray([x for x in values if x is not None and np.isfinite(x)], dtype=np.float64)
    if len(v) == 0:
        return float("nan"), float("nan")
    if len(v) == 1:
        return float(v[0]), float("nan")
    half = float(stats.t.ppf(0.975, len(v) - 1) * v.std(ddof=1) / np.sqrt(len(v)))
    return float(v.mean()), half


@dataclass(frozen=True)
class Combined:
    """A finding over seeds: the first seed's finding (its text), the verdict over seeds (on
    the pooled runs where the finding has evidence), each seed's verdict, the effect's mean ±
    95% CI half-width over seeds and the pooled decisions in words (``interval``)."""

    finding: Finding
    verdict: str
    seed_verdicts: tuple[str, ...]
    mean: float
    half_width: float
    interval: str = ""

    @property
    def effect(self) -> str:
        f = self.finding
        if f.value is None or not np.isfinite(self.mean):
            return "–"
        ci = "" if not np.isfinite(self.half_width) else f" ± {self.half_width:.3g}"
        return f"{self.mean:.3g}{ci} ({f.value_label})"

    def as_finding(self) -> Finding:
        return replace(self.finding, verdict=self.verdict, interval=self.interval)


def judge(found: list[Finding]) -> tuple[str, str]:
    """The verdict of findings with evidence (one per seed), part by part — on the runs
    pooled, or on the seeds' estimates when the finding rests on a fitted object per seed —
    and the decisions in words."""
    first = found[0]
    if any(len(g.evidence) != len(first.evidence) for g in found) or not first.evidence:
        raise ValueError(f"every seed's finding needs the same parts of evidence: {first.claim}")
    decisions = []
    for i, part in enumerate(first.evidence):
        items = [g.evidence[i] for g in found]
        decisions.append(
            part.seed_level(items, first.fitted) if first.fitted else part.pool(items).decide()
        )
    verdict = (first.parts or join)([d.verdict for d in decisions])
    return verdict, "; ".join(d.text() for d in decisions)


def combine(per_seed: list[list[Finding]]) -> list[Combined]:
    """Match the seeds' findings (same section and claim, in the first seed's order) and
    combine them: decided on the pooled runs (or the seeds' fits) where they carry evidence,
    else the common verdict, or inconclusive when the seeds disagree."""
    first = per_seed[0]
    out = []
    for f in first:
        same = [next((g for g in fs if g.key == f.key), None) for fs in per_seed]
        found = [g for g in same if g is not None]
        verdicts = tuple(g.verdict for g in found)
        interval = ""
        if f.evidence:
            verdict, interval = judge(found)
        else:
            verdict = verdicts[0] if len(set(verdicts)) == 1 else "inconclusive"
        mean, half = mean_ci([g.value for g in found if g.value is not None])
        out.append(Combined(f, verdict, verdicts, mean, half, interval))
    return out


def join(verdicts: list[str]) -> str:
    """Rule 'join', the one way parts of a claim combine, symmetric in holds and differs:
    their common verdict; **inconclusive** when some parts are undecided and the decided ones
    agree (whichever way they agree); **partly** when the decided parts disagree."""
    if not verdicts:
        raise ValueError("a claim needs at least one part to join")
    if len(set(verdicts)) == 1:
        return verdicts[0]
    decided = {v for v in verdicts if v != "inconclusive"}
    return "inconclusive" if len(decided) == 1 else "partly"


def chain_verdict(verdicts: list[str], groups: int = 1) -> str:
    """Rule 'chain': ``verdicts`` are the links' ``ci``-verdicts, group after group (equal
    sizes): each group's links joined (:func:`join`), then the groups."""
    if groups < 1 or not verdicts or len(verdicts) % groups:
        raise ValueError(f"{len(verdicts)} links do not split into {groups} equal groups")
    size = len(verdicts) // groups
    return join([join(verdicts[i * size : (i + 1) * size]) for i in range(groups)])


def readings_verdict(first: str, second: str) -> str:
    """Two readings the paper leaves open (e.g. the GMM's dimension): their common verdict,
    else **inconclusive**."""
    return first if first == second else "inconclusive"


def readings_parts_verdict(verdicts: list[str], first: int = 2) -> str:
    """Two readings of one claim, each of several parts: the first ``first`` verdicts are
    the first reading's parts, the rest the second's; each reading joined by :func:`join`,
    the two by :func:`readings_verdict`."""
    if not 0 < first < len(verdicts):
        raise ValueError(f"first must be 1…{len(verdicts) - 1}; got {first}")
    return readings_verdict(join(verdicts[:first]), join(verdicts[first:]))


def compromise_verdict(verdicts: list[str], targets: int = 2, others: int = 2) -> str:
    """Rule 'compromise': a setting is a compromise of two criteria when no other setting
    beats it on both and it beats each other setting on at least one. ``verdicts``: per
    target, per other setting, (criterion 1, criterion 2) of ``ci``-verdicts of (other −
    ours), lower is better (**holds**: ours better, **differs**: the other better). Per
    target: **differs** when some other setting is better on both, **holds** when ours is
    better than every other on one, **inconclusive** otherwise; the targets joined
    (:func:`join`)."""
    if len(verdicts) != targets * others * 2:
        raise ValueError(f"expected {targets * others * 2} verdicts; got {len(verdicts)}")
    pairs = [verdicts[i : i + 2] for i in range(0, len(verdicts), 2)]
    per_target = []
    for t in range(targets):
        ps = pairs[t * others : (t + 1) * others]
        dominated = any(p == ["differs", "differs"] for p in ps)
        optimal = all("holds" in p for p in ps)
        per_target.append("differs" if dominated else "holds" if optimal else "inconclusive")
    return join(per_target)
