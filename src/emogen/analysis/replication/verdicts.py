"""The verdict rules, written down once, and the combination of several seeds' findings.

A finding with :attr:`~emogen.analysis.replication.findings.Finding.evidence` (per-run data and
the test that decides on them, :mod:`~emogen.analysis.replication.intervals`) is decided on
the runs of all seeds pooled: its verdict is the test's on the pooled runs, and each seed's
own verdict is kept as a robustness column. A finding without evidence keeps the seeds'
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
    "ci": "a difference with a direction: **holds** when the 95% CI of our difference lies on "
    "the paper's side of 0; **inconclusive** when it includes 0; **differs** when it lies on "
    "the other side",
    "number": "a value the paper gives (μ ± σ): the 95% CI of our μ, as a distance from the "
    "paper's μ in pooled σ: **holds** when the whole CI lies within 0.5 σ; **partly** within "
    "1 σ; **differs** when it lies wholly beyond 1 σ; **inconclusive** otherwise",
    "direction": "a qualitative claim: **partly** when our direction agrees (the paper's "
    "qualitative magnitude — 'excellent', 'cannot match' — cannot be scored), **differs** "
    "otherwise",
    "threshold": "a stated level: **holds** at or past the level the claim names (given in the "
    "claim); **partly** past its weaker level; **differs** otherwise",
    "tost": "no difference claimed, tested for equivalence (TOST, α = 0.05) against a stated "
    "margin: **holds** when the 90% CI lies inside ±margin; **differs** when it lies wholly "
    "outside; **inconclusive** otherwise",
    "noninferior": "'not worse than' (lower is better): **holds** when the 90% CI's upper end "
    "is below the margin; **differs** when its lower end is above it; **inconclusive** "
    "otherwise",
    "level": "a share against a stated level: **holds** when its 95% CI lies at or past the "
    "level; **partly** when past the weaker level only; **differs** when wholly short of the "
    "weaker level; **inconclusive** otherwise",
    "compromise": "a setting as a compromise of two criteria (lower is better), paired CIs "
    "against each other setting: **differs** when another is significantly better on both; "
    "**holds** when it is significantly better than every other on at least one, for every "
    "target; **partly** for some targets; **inconclusive** otherwise",
    "chain": "orderings (x₁ > x₂ > …, per group — a target, a generation), each link a paired "
    "95% CI (means: t; SDs: bootstrap): a group **holds** when every link holds; **holds** when "
    "every group does; **partly** when at least the stated number of groups do (one, unless "
    "the claim says); **differs** when fewer do and some link lies on the other side of 0; "
    "**inconclusive** otherwise",
    "band": "a distance or residual (lower is better) against stated levels: **holds** when "
    "its 95% CI lies below the level; **partly** when below the weaker level only; "
    "**differs** when it lies wholly at or beyond the weaker level; **inconclusive** otherwise",
    "kl": "KL steps: a rise counts only where KL(P_g ‖ P_g−1) grows by more than the KL "
    "noise floor (95th percentile of the KL of two same-size samples of one distribution); "
    "**holds** when the paper's pattern of rises holds for both initialisations, **partly** "
    "for one, **differs** for none",
}


def ci_verdict(lo: float, hi: float, paper_sign: int) -> str:
    """Rule 'ci': the 95% CI (lo, hi) of our difference against the paper's sign (±1)."""
    if lo <= 0 <= hi:
        return "inconclusive"
    return "holds" if (lo > 0) == (paper_sign > 0) else "differs"


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
    """The verdict of findings with evidence (one per seed) on their runs pooled, part by part,
    and the decisions in words."""
    first = found[0]
    if any(len(g.evidence) != len(first.evidence) for g in found) or not first.evidence:
        raise ValueError(f"every seed's finding needs the same parts of evidence: {first.claim}")
    decisions = [
        first.evidence[i].pool([g.evidence[i] for g in found]).decide()
        for i in range(len(first.evidence))
    ]
    verdicts = [d.verdict for d in decisions]
    verdict = (first.parts or parts_verdict)(verdicts)
    return verdict, "; ".join(d.text() for d in decisions)


def combine(per_seed: list[list[Finding]]) -> list[Combined]:
    """Match the seeds' findings (same section and claim, in the first seed's order) and
    combine them: decided on the pooled runs where they carry evidence, else the common
    verdict, or inconclusive when the seeds disagree."""
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


def chain_verdict(verdicts: list[str], groups: int = 1, partly_at: int = 1) -> str:
    """Rule 'chain': ``verdicts`` are the links' ``ci``-verdicts, group after group (equal
    sizes). A group holds when all its links hold. **holds** when every group holds;
    **partly** when at least ``partly_at`` groups hold; **differs** when fewer do and some link
    differs; **inconclusive** otherwise."""
    if groups < 1 or not verdicts or len(verdicts) % groups:
        raise ValueError(f"{len(verdicts)} links do not split into {groups} equal groups")
    if not 1 <= partly_at <= groups:
        raise ValueError(f"partly_at must be 1…{groups}; got {partly_at}")
    size = len(verdicts) // groups
    held = sum(
        all(v == "holds" for v in verdicts[i * size : (i + 1) * size]) for i in range(groups)
    )
    if held == groups:
        return "holds"
    if held >= partly_at:
        return "partly"
    return "differs" if "differs" in verdicts else "inconclusive"


def parts_verdict(verdicts: list[str]) -> str:
    """A claim of several parts: their common verdict; else **partly** when some part holds,
    **differs** when some part differs, **inconclusive** otherwise."""
    if len(set(verdicts)) == 1:
        return verdicts[0]
    return (
        "partly" if "holds" in verdicts else "differs" if "differs" in verdicts else "inconclusive"
    )


def main_part_verdict(verdicts: list[str], n_main: int = 1) -> str:
    """A claim whose first ``n_main`` parts are its point and the rest qualify it: the main
    parts' common verdict decides when it is **differs** or **inconclusive** (a qualifying
    part cannot rescue a failed point); when the main parts hold, **holds** if every other
    part holds too, else **partly**."""
    if not 0 < n_main <= len(verdicts):
        raise ValueError(f"n_main must be 1…{len(verdicts)}; got {n_main}")
    main = verdicts[:n_main]
    if "differs" in main:
        return "differs"
    if "inconclusive" in main:
        return "inconclusive"
    if all(v == "holds" for v in verdicts):
        return "holds"
    return "partly"


def readings_verdict(first: str, second: str) -> str:
    """Two readings the paper leaves open (e.g. the GMM's dimension): their common verdict,
    else **inconclusive**."""
    return first if first == second else "inconclusive"


def readings_parts_verdict(verdicts: list[str], first: int = 2) -> str:
    """Two readings of one claim, each of several parts: the first ``first`` verdicts are
    the first reading's parts, the rest the second's; each reading joined by
    :func:`parts_verdict`, the two by :func:`readings_verdict`."""
    if not 0 < first < len(verdicts):
        raise ValueError(f"first must be 1…{len(verdicts) - 1}; got {first}")
    return readings_verdict(parts_verdict(verdicts[:first]), parts_verdict(verdicts[first:]))


def compromise_verdict(verdicts: list[str], targets: int = 2, others: int = 2) -> str:
    """Rule 'compromise': a setting is a compromise of two criteria when no other setting
    beats it on both (it is not dominated) and it beats each other setting on at least one.
    ``verdicts``: per target, per other setting, (criterion 1, criterion 2) of
    ``ci``-verdicts of (other − ours), lower is better (**holds**: ours significantly better,
    **differs**: the other significantly better). **differs** when some other setting is
    significantly better on both for some target; **holds** when it is significantly beaten
    on one criterion by every other setting for every target; **partly** for some targets;
    **inconclusive** otherwise."""
    if len(verdicts) != targets * others * 2:
        raise ValueError(f"expected {targets * others * 2} verdicts; got {len(verdicts)}")
    pairs = [verdicts[i : i + 2] for i in range(0, len(verdicts), 2)]
    per_target = [pairs[t * others : (t + 1) * others] for t in range(targets)]
    if any(p == ["differs", "differs"] for p in pairs):
        return "differs"
    optimal = [all("holds" in p for p in ps) for ps in per_target]
    return "holds" if all(optimal) else "partly" if any(optimal) else "inconclusive"
