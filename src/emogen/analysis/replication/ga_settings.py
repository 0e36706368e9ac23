"""Section IV-C: how the GA's settings and the target shape convergence — activation ranges
in the initialisation (Table IV), target complexity and GA noise (Table V, Fig. 18), and
selection pressure (the classical variant)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from emogen.analysis import paper
from emogen.analysis.noise import GANoise, pooled_noise
from emogen.analysis.paper_targets import paper_targets
from emogen.analysis.replication.conditions import Condition, ConditionRunner, ConditionSpec
from emogen.analysis.replication.findings import Finding, cohen_d, graded, pm
from emogen.analysis.replication.geometry import FaceGeometry
from emogen.analysis.replication.intervals import (
    Direction,
    Equivalence,
    Evidence,
    SpreadDirection,
    judged,
)
from emogen.analysis.replication.verdicts import compromise_verdict, number_verdict

RANGES = ((1, 3), (3, 8), (8, 16))
T1, T2 = "target 1", "target 2"


@dataclass(frozen=True, eq=False)
class ActivationRanges:
    """Table IV analogue: μ0, σ0, μ10, σ10 per (target, range), the table, the findings."""

    stats: dict[tuple[str, tuple[int, int]], tuple[float, float, float, float]]
    table: pd.DataFrame
    findings: list[Finding]


def activation_ranges(runner: ConditionRunner) -> ActivationRanges:
    targets = paper_targets(runner.rig)
    res, sims = {}, {}
    rows = []
    for t in (T1, T2):
        for rng_ in RANGES:
            s = runner.condition(f"{t} {rng_}", targets[t], ConditionSpec(activation_range=rng_))
            sims[(t, rng_)] = s
            m0, s0 = s.stats(0)
            m10, s10 = s.stats()
            res[(t, rng_)] = (m0, s0, m10, s10)
            p = paper.TABLE_IV[t][rng_]
            rows.append(
                {
                    "target": t,
                    "active genes": f"{rng_[0]}–{rng_[1]}",
                    "μ0": m0,
                    "σ0": s0,
                    "μ10": m10,
                    "σ10": s10,
                    "paper μ0, σ0, μ10, σ10": ", ".join(f"{v:.3f}" for v in p),
                }
            )
    return ActivationRanges(res, pd.DataFrame(rows), [*_range_findings(res), _recommended(sims)])


def _range_findings(
    res: dict[tuple[str, tuple[int, int]], tuple[float, float, float, float]],
) -> list[Finding]:
    def falls(i: int, t: str) -> bool:
        v = [res[(t, g)][i] for g in RANGES]
        return bool(v[0] > v[1] > v[2])

    def chain(i: int, t: str) -> str:
        return " > ".join(f"{res[(t, g)][i]:.3f}" for g in RANGES)

    best = {t: min(RANGES, key=lambda g: res[(t, g)][2]) for t in (T1, T2)}
    fewest = [best[t] == (1, 3) for t in (T1, T2)]
    return [
        Finding(
            "Table IV",
            "more initial activations lower the initial bias μ0",
            "0.752 > 0.744 > 0.737; 0.557 > 0.530 > 0.501",
            f"{chain(0, T1)}; {chain(0, T2)}",
            graded(falls(0, T1) and falls(0, T2), falls(0, T1) or falls(0, T2)),
            rule="order: μ0 falls over 1–3, 3–8, 8–16 for both targets; partly: for one",
            value=float(
                np.mean([res[(t, RANGES[0])][0] - res[(t, RANGES[-1])][0] for t in (T1, T2)])
            ),
            value_label="μ0 (1–3) − μ0 (8–16), mean of targets",
        ),
        Finding(
            "Table IV",
            "more initial activations make the bias more consistent (σ0 falls)",
            "0.370 > 0.238 > 0.150; 0.132 > 0.129 > 0.102",
            f"{chain(1, T1)}; {chain(1, T2)}",
            graded(falls(1, T1) and falls(1, T2), falls(1, T1) or falls(1, T2)),
            rule="order: σ0 falls over the ranges for both targets; partly: for one",
            value=float(
                np.mean([res[(t, RANGES[0])][1] - res[(t, RANGES[-1])][1] for t in (T1, T2)])
            ),
            value_label="σ0 (1–3) − σ0 (8–16), mean of targets",
        ),
        Finding(
            "Table IV",
            "the fewest activations (1–3) converge best (lowest μ10), for both targets",
            "μ10 0.362 / 0.222 at 1–3",
            "best μ10: "
            + "; ".join(
                f"{t} {best[t][0]}–{best[t][1]} ({res[(t, best[t])][2]:.3f})" for t in (T1, T2)
            ),
            graded(all(fewest), any(fewest)),
            ""
            if all(fewest)
            else "our twelve-gene target covers 40% of our 30-gene space: richer random "
            "faces already overlap it (docs/ga.md)",
            rule="order: 1–3 has the lowest μ10 for both targets; partly: for one",
            value=float(sum(fewest)),
            value_label="targets best at 1–3",
        ),
        Finding(
            "Table IV",
            "1–3 activations lower the consistency (raise σ10) for the simple target 1",
            "σ10 0.206 (1–3) > 0.162 (3–8)",
            f"σ10 {res[(T1, (1, 3))][3]:.3f} (1–3) vs {res[(T1, (3, 8))][3]:.3f} (3–8)",
            "holds" if res[(T1, (1, 3))][3] > res[(T1, (3, 8))][3] else "differs",
            rule="order: σ10 (1–3) > σ10 (3–8) for target 1",
            value=res[(T1, (1, 3))][3] - res[(T1, (3, 8))][3],
            value_label="σ10 (1–3) − (3–8)",
        ),
    ]


def _recommended(sims: dict[tuple[str, tuple[int, int]], Condition]) -> Finding:
    """The paper's recommended range as a compromise of accuracy (μ10) and consistency (σ10):
    not beaten on both by another range, and better than each other range on one."""
    mid = (3, 8)
    evidence = [
        Evidence(test, (sims[(t, g)].final_errors, sims[(t, mid)].final_errors))
        for t in (T1, T2)
        for g in RANGES
        if g != mid
        for test in (Direction(+1), SpreadDirection(+1, seed=32))
    ]

    def said(t: str) -> str:
        return ", ".join(f"{g[0]}–{g[1]}: {pm(*sims[(t, g)].stats())}" for g in RANGES)

    return judged(
        "Table IV",
        "3–8 active genes is the best compromise of accuracy (μ10) and consistency (σ10)",
        "recommended default 3–8",
        f"μ10 ± σ10 {T1}: {said(T1)}; {T2}: {said(T2)}",
        evidence,
        "compromise, paired per run (μ10: t; σ10: bootstrap), each other range against 3–8: "
        "differs when one beats 3–8 on both; holds when 3–8 beats every other range on one, "
        "for both targets; partly for one",
        parts=compromise_verdict,
    )


@dataclass(frozen=True, eq=False)
class ComplexityNoise:
    """Table V analogue: a condition per target (in order of complexity), the table, the
    pooled GA noise of the complex targets, the findings."""

    conditions: dict[str, Condition]
    table: pd.DataFrame
    noise: GANoise
    findings: list[Finding]


def complexity_noise(runner: ConditionRunner, geometry: FaceGeometry) -> ComplexityNoise:
    sims = {t: runner.condition(t, named) for t, named in paper_targets(runner.rig).items()}
    fits = {t: geometry.intensity_fit(s.mean_face, s.target) for t, s in sims.items()}
    rows = []
    for t, s in sims.items():
        label, pmu, psd = paper.TABLE_V[t]
        mu, sd = s.stats()
        rows.append(
            {
                "target": t,
                "paper target": label,
                "μ": mu,
                "σ": sd,
                "paper μ": pmu,
                "paper σ": psd,
                "CD(mean face, target)": s.mean_face_cd,
                "|mean| / |target|": float(np.linalg.norm(s.mean_face) / np.linalg.norm(s.target)),
                "intensity scale ×": fits[t][0],
                "residual off the line": fits[t][1],
            }
        )
    parts = [GANoise.from_errors(sims[t].final_errors, t) for t in (T2, "dense happy")]
    noise = pooled_noise(parts, "mean of target 2 and the dense happy target")
    findings = _complexity_findings(sims, noise, fits)
    return ComplexityNoise(sims, pd.DataFrame(rows), noise, findings)


def _complexity_findings(
    sims: dict[str, Condition], noise: GANoise, fits: dict[str, tuple[float, float]]
) -> list[Finding]:
    mus = [s.stats()[0] for s in sims.values()]
    sds = [s.stats()[1] for s in sims.values()]
    mono_mu, mono_sd = bool(np.all(np.diff(mus) < 0)), bool(np.all(np.diff(sds) < 0))
    pmu, psd = paper.GA_NOISE
    threshold, _ = number_verdict(noise.mean, noise.sd, pmu, psd)
    on_line = all(res < 0.35 for _, res in fits.values())
    scale = fits["dense happy"][0]
    return [
        Finding(
            "Table V",
            "GA noise falls with target complexity (μ and σ)",
            "μ 0.426 > 0.267 > 0.237 > 0.222; σ 0.164 > 0.100 > 0.076 > 0.055",
            "μ "
            + " > ".join(f"{m:.3f}" for m in mus)
            + "; σ "
            + " > ".join(f"{s:.3f}" for s in sds),
            graded(mono_mu and mono_sd, mono_mu or mono_sd),
            rule="order: μ and σ fall with complexity; partly: one of the two",
            value=mus[0] - mus[-1],
            value_label="μ target 1 − dense",
        ),
        Finding(
            "Table V",
            "GA-noise threshold ≈ 0.2 ± 0.065 CD (mean of the complex targets)",
            f"{pmu} ± {psd}",
            noise.label,
            threshold,
            "the paper's own Table V gives (0.237 + 0.222)/2 = 0.23 ± 0.066 for the same two "
            "targets, not 0.2; the threshold is model-specific: compute it for the model a study "
            "uses (`emogen analyse` simulates it)",
            rule="number: |Δμ| / pooled σ against 0.2 ± 0.065",
            value=noise.mean,
            value_label="our threshold μ",
        ),
        Finding(
            "Fig. 18",
            "the mean final face lies on the target's intensity line; the dense target's even "
            "matches its intensity",
            "visually on the intensity scale of the target; 125-shape intensity close",
            "vertex residual off the line (0 = on it): "
            + ", ".join(f"{t} {res:.2f}" for t, (_, res) in fits.items())
            + f"; dense intensity ×{scale:.2f}",
            graded(on_line and 0.8 <= scale <= 1.25, on_line),
            rule="threshold: every residual < 0.35 and dense intensity ×0.8–1.25; partly: the "
            "former",
            value=max(r for _, r in fits.values()),
            value_label="largest residual",
        ),
        _profiles(sims),
    ]


def _profiles(sims: dict[str, Condition]) -> Finding:
    """Fig. 18's per-generation profiles: more complex targets lower at every generation."""
    mu = np.array([s.errors.mean(axis=0) for s in sims.values()])  # (targets, G + 1)
    ordered = [bool(np.all(np.diff(mu[:, g]) < 0)) for g in range(mu.shape[1])]
    k = sum(ordered)
    return Finding(
        "Fig. 18",
        "complex targets are closer from the first generations on (per-generation profiles)",
        "earlier matches for more active shapes; lower error throughout",
        f"mean error falls with complexity in {k} of {len(ordered)} generations (0–10); gen 0: "
        + " > ".join(f"{v:.2f}" for v in mu[:, 0]),
        "holds" if k == len(ordered) else "partly" if k >= len(ordered) / 2 else "differs",
        rule="order: μ_g falls with complexity in every generation; partly: in at least half",
        value=float(k),
        value_label="generations in order",
    )


@dataclass(frozen=True, eq=False)
class SelectionPressure:
    """Final CD error of EmoGen's GA against the classical variant per target: the table,
    Cohen's d (classical − EmoGen) per target, the findings."""

    table: pd.DataFrame
    cohen_d: dict[str, float]
    findings: list[Finding]


def selection_pressure(runner: ConditionRunner) -> SelectionPressure:
    targets = paper_targets(runner.rig)
    rows, ds, pairs = [], {}, []
    for t in (T1, "target 3", T2):
        e = runner.condition(t, targets[t])
        c = runner.condition(f"classical {t}", targets[t], ConditionSpec(variant="classical"))
        pairs.append((c.final_errors, e.final_errors))
        d = cohen_d(c.final_errors, e.final_errors)
        p = stats.mannwhitneyu(c.final_errors, e.final_errors).pvalue
        ds[t] = d
        rows.append(
            {
                "target": t,
                "EmoGen μ10 ± σ10": pm(*e.stats()),
                "classical μ10 ± σ10": pm(*c.stats()),
                "Cohen's d": d,
                "Mann–Whitney p": float(p),
            }
        )
    better = [t for t, d in ds.items() if d < -0.2]
    worse = [t for t, d in ds.items() if d > 0.2]
    note = "; ".join(
        part
        for part in (
            f"classical better on {', '.join(better)}" if better else "",
            f"classical worse on {', '.join(worse)}" if worse else "",
        )
        if part
    )
    finding = judged(
        "Selection pressure",
        "fitness ranking does not improve convergence: its absence is no bottleneck",
        "accuracy unaffected",
        "d (classical − EmoGen) " + ", ".join(f"{t}: {d:+.2f}" for t, d in ds.items()),
        [Evidence(Equivalence(margin_sd=0.2), pair) for pair in pairs],
        "tost, paired per run, per target: μ10 classical − EmoGen within ±0.2 pooled SD; "
        "parts joined: all hold → holds, some → partly",
        note=note,
        value=float(max(abs(d) for d in ds.values())),
        value_label="largest |d|",
    )
    return SelectionPressure(pd.DataFrame(rows), ds, [finding])
