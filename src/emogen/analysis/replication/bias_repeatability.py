"""Section IV-C: the initial target bias and the repeatability of the final faces, with fixed
sets and protocol initialisation (Table III)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np
import pandas as pd

from emogen.analysis import paper
from emogen.analysis.paper_targets import TARGET_1
from emogen.analysis.repeatability import BIN_LABELS, repeatability_bins
from emogen.analysis.replication.baselines import chance_faces
from emogen.analysis.replication.conditions import Condition, ConditionRunner, ConditionSpec
from emogen.analysis.replication.findings import Finding
from emogen.analysis.replication.intervals import Direction, Evidence, judged
from emogen.analysis.replication.repeat_intervals import BinContrast, BinShares
from emogen.analysis.replication.verdicts import (
    chain_verdict,
    readings_parts_verdict,
)

Row = tuple[str, int | None, str]  # (initialisation, fixed set, target)
#: "far more" bias: half the paper's gap between protocol and fixed set 3 (0.55 − 0.38)
FAR = 0.085


@dataclass(frozen=True, eq=False)
class BiasRepeatability:
    """``average_target``: our analogue of the paper's average expression; ``active_per_face``
    of fixed sets 1 and 3; per Table III row: ``shares`` (%, per bin) and ``bias``; the table
    and the findings."""

    average_target: dict[str, float]
    active_per_face: dict[int, float]
    shares: dict[Row, np.ndarray]
    bias: dict[Row, float]
    table: pd.DataFrame
    findings: list[Finding]

    @property
    def bins_table(self) -> pd.DataFrame:
        """Shares per bin, one row per Table III row (for the figure)."""
        return pd.DataFrame(
            [self.shares[k] for k in self.shares],
            columns=list(BIN_LABELS),
            index=[
                f"{i} {o or ''} · {t} · bias {self.bias[(i, o, t)]:.2f}"
                for (i, o, t) in self.shares
            ],
        )


#: the average target is built from one seed's own simulated trials: findings on it are
#: decided at the level of that construction (rule 'seed level')
AVERAGE = "average target (the mean face of that seed's 80 simulated trials)"


def active_per_face(runner: ConditionRunner, option: int) -> float:
    """Mean number of active shapes per face of packaged fixed set ``option``."""
    from emogen.ga.init import read_fixed_sets

    sets = read_fixed_sets(None, runner.rig)
    w = runner.rig.expand(sets[option - 1])
    return float((w > 0).sum(axis=1).mean())


def average_target(runner: ConditionRunner) -> dict[str, float]:
    """The analogue of the paper's 'average expression target': the mean final face of 80
    simulated-participant trials evolving happy, 40 from fixed and 40 from protocol
    initialisation."""
    seed = runner.settings.seed
    a = runner.participants("happy", 40, seed=seed * 1000 + 7, init="fixed").faces
    b = runner.participants("happy", 40, seed=seed * 1000 + 8, init="protocol").faces
    mean = np.concatenate([a, b]).mean(axis=0)
    return {s: float(v) for s, v in zip(runner.rig.shape_names, mean, strict=True) if v > 1e-6}


def bias_repeatability(runner: ConditionRunner) -> BiasRepeatability:
    avg = average_target(runner)
    targets = {"target 1": TARGET_1, "average": avg}
    rows, shares, biases, conds = [], {}, {}, {}
    for init, option, tname, p_bias, p_bins in paper.TABLE_III:
        spec = ConditionSpec(init="fixed", fixed_option=option) if init == "fixed" else None
        s = runner.condition(f"{init} {option} {tname}", targets[tname], spec)
        b = repeatability_bins(s.final) * 100
        key = (init, option, tname)
        shares[key], biases[key], conds[key] = b, float(s.best_initial.mean()), s
        rows.append(
            {
                "init": init,
                "fixed set": option or "–",
                "target": tname,
                "bias": biases[key],
                "paper bias": p_bias,
                **{f"{lab} %": float(v) for lab, v in zip(BIN_LABELS, b, strict=True)},
                "paper bins %": " / ".join(f"{x:g}" for x in p_bins),
            }
        )
    return BiasRepeatability(
        average_target=avg,
        active_per_face={o: active_per_face(runner, o) for o in (1, 3)},
        shares=shares,
        bias=biases,
        table=pd.DataFrame(rows),
        findings=_findings(shares, biases, conds, runner.settings.seed, _chance_bins(runner)),
    )


def _chance_bins(runner: ConditionRunner) -> str:
    """The bins of faces with no target behind them (chance), in words."""
    rng = np.random.default_rng(runner.settings.seed * 1000 + 3)
    bins = repeatability_bins(chance_faces(runner.rig, 500, rng)) * 100
    return "chance (500 faces as protocol initialisation draws them, no target): bins " + (
        " / ".join(f"{b:.1f}" for b in bins) + " %"
    )


def _findings(
    shares: dict[Row, np.ndarray],
    biases: dict[Row, float],
    conds: dict[Row, Condition],
    seed: int,
    chance: str,
) -> list[Finding]:
    best_fixed = min((("fixed", o, "average") for o in (1, 3)), key=lambda k: biases[k])
    fixed_avg, prot_avg = biases[best_fixed], biases[("protocol", None, "average")]
    prot_bias = conds[("protocol", None, "average")].best_initial
    fixed_bias = conds[best_fixed].best_initial
    fixed_keys, prot_keys = ([k for k in shares if k[0] == i] for i in ("fixed", "protocol"))
    most = min(fixed_keys, key=lambda k: biases[k])
    first_fixed = shares[most][0]
    a, b = shares[("fixed", 1, "target 1")], shares[("fixed", 3, "target 1")]
    tvd = 0.5 * float(np.abs(a - b).sum())
    group = np.full(len(conds[most].final), seed)
    return [
        judged(
            "Table III",
            "protocol initialisation hardly reaches a high bias: a fixed set can bias far more",
            "average target: 0.55 (protocol) vs 0.38 (fixed set 3)",
            f"average target: {prot_avg:.2f} (protocol) vs {fixed_avg:.2f} (best fixed set)",
            [
                Evidence(Direction(+1), (prot_bias, fixed_bias)),
                Evidence(Direction(+1), (prot_bias, fixed_bias + FAR)),
            ],
            "ci, paired per run (average target): initial bias protocol − the best fixed "
            f"set's > 0, and > {FAR} ('far more': half the paper's gap of 0.17), paired t 95% "
            "CIs (SESOI 0.2 SD); parts joined (rule join)",
            note="our simulated participants build happy faces from the same building blocks "
            "that protocol initialisation draws its two happy faces from",
            value=prot_avg - fixed_avg,
            value_label="bias protocol − fixed",
            fitted=AVERAGE,
        ),
        judged(
            "Table III",
            "with a fixed set, a high bias piles the final faces into the first bin",
            "bias 0.38: 99% of pairs in [0, 0.25)",
            f"bias {biases[most]:.2f}: {first_fixed:.1f}% (protocol rows: "
            + ", ".join(f"{shares[k][0]:.1f}%" for k in prot_keys)
            + ")",
            [Evidence(BinShares("first_at_least", 50, seed=24), (group, conds[most].final))]
            + [
                Evidence(
                    BinShares("first_above", seed=24), (group, conds[most].final, conds[k].final)
                )
                for k in prot_keys
            ],
            "level and ci, bootstrap over runs within seeds (95%): the highest-bias fixed row's "
            "first-bin share ≥ 50% and above each protocol row's (SESOI 5 points); parts joined "
            "(rule join)",
            note=chance,
            value=float(first_fixed),
            value_label="first-bin % at the highest fixed bias",
            fitted=AVERAGE if most[2] == "average" else "",
        ),
        _sensitivity(shares, biases, conds, seed),
        judged(
            "Table III",
            "initial complexity does not change repeatability at similar bias",
            "fixed sets 1 and 3, target 1: bins differ by 4.7 points (TVD)",
            f"bias {biases[('fixed', 1, 'target 1')]:.2f} and "
            f"{biases[('fixed', 3, 'target 1')]:.2f}: TVD {tvd:.1f} points",
            [
                Evidence(
                    BinShares("tvd_below", 10, 20, seed=26),
                    (group, *(conds[("fixed", o, "target 1")].final for o in (1, 3))),
                )
            ],
            "band, bootstrap over runs within seeds (95%): the TVD of the two "
            "fixed sets' bins (target 1) below 10 points holds, below 20 partly, at or above 20 "
            "differs",
            note=chance,
            value=tvd,
            value_label="TVD, points",
        ),
        _absolute(shares, conds, group, chance),
    ]


def _sensitivity(
    shares: dict[Row, np.ndarray],
    biases: dict[Row, float],
    conds: dict[Row, Condition],
    seed: int,
) -> Finding:
    """Table III #25 in both readings (:mod:`~emogen.analysis.replication.repeat_intervals`):
    matched bias (each protocol row against the fixed row nearest in bias) and within
    initialisation (each initialisation's first-bin slope from target 1 to the average)."""

    def slope(init: str, option: int | None) -> float:
        lo, hi = (init, option, "target 1"), (init, option, "average")
        return float((shares[hi][0] - shares[lo][0]) / max(biases[lo] - biases[hi], 1e-9))

    def rows(*keys: Row) -> tuple[np.ndarray, ...]:
        return tuple(a for k in keys for a in (conds[k].final, conds[k].best_initial))

    p1, pa = ("protocol", None, "target 1"), ("protocol", None, "average")
    fixed_rows = [k for k in shares if k[0] == "fixed"]
    nearest = {p: min(fixed_rows, key=lambda k: abs(biases[k] - biases[p])) for p in (pa, p1)}
    group = np.full(len(conds[p1].best_initial), seed)
    evidence = [
        Evidence(BinContrast("matched", +1, seed=25), (group, *rows(p1, pa, p, nearest[p])))
        for p in (pa, p1)
    ] + [
        Evidence(
            BinContrast("slope", -1, seed=25),
            (group, *rows(p1, pa, ("fixed", o, "target 1"), ("fixed", o, "average"))),
        )
        for o in (1, 3)
    ]
    matched = "; ".join(
        f"protocol {biases[p]:.2f} ({shares[p][0]:.1f}%) vs fixed set {k[1]} {k[2]} "
        f"{biases[k]:.2f} ({shares[k][0]:.1f}%)"
        for p, k in nearest.items()
    )
    prot = slope("protocol", None)
    return judged(
        "Table III",
        "protocol repeatability is less sensitive to bias: fewer identical results as bias grows",
        "first bin per unit bias: protocol (2.0 → 6.6%) / 0.19 = 24; fixed set 1 (1.0 → 29.8%) "
        "/ 0.43 = 67; set 3 (1.4 → 99%) / 0.49 = 199",
        f"matched bias: {matched}; within initialisation, first-bin points per unit bias: "
        f"protocol {prot:.0f}; fixed set 1 {slope('fixed', 1):.0f}, set 3 {slope('fixed', 3):.0f}",
        evidence,
        "ci per part, bootstrap over runs within seeds (95%): matched bias — each protocol "
        "row against the fixed row nearest in bias, the fixed row's first-bin share above "
        "protocol's moved along protocol's own slope to the fixed row's bias; within "
        "initialisation — protocol's slope below each fixed set's; readings joined: their "
        "common verdict, else inconclusive",
        note="the paper's arithmetic is the within-initialisation reading; at matched bias "
        "its own rows (protocol 0.55: 6.6%, fixed set 1 0.57: 29.8%) read the same way",
        parts=readings_parts_verdict,
        value=prot,
        value_label="protocol first-bin points per unit bias",
        fitted=AVERAGE,
    )


def _absolute(
    shares: dict[Row, np.ndarray], conds: dict[Row, Condition], group: np.ndarray, chance: str
) -> Finding:
    """Table III's bins themselves, row by row: the TVD of our row's bins from the paper's,
    bootstrapped over runs within seeds."""
    tvds = {
        (init, option, t): 0.5 * float(np.abs(shares[(init, option, t)] - np.array(bins)).sum())
        for init, option, t, _, bins in paper.TABLE_III
    }
    evidence = [
        Evidence(
            BinShares("tvd_to", 10, 20, seed=31, reference=tuple(bins)),
            (group, conds[(init, option, t)].final),
        )
        for init, option, t, _, bins in paper.TABLE_III
    ]
    return judged(
        "Table III",
        "the repeatability bins themselves (absolute shares per row)",
        "six rows of bin shares",
        "TVD from the paper's row: "
        + ", ".join(
            f"{i} {o or ''} {t}: {v:.0f}".replace("  ", " ") for (i, o, t), v in tvds.items()
        )
        + " points",
        evidence,
        "band per row, bootstrap over runs within seeds (95%): the TVD of our row's bins from "
        "the paper's below 10 points holds, below 20 partly, at or above 20 differs; rows "
        "joined (rule join)",
        parts=partial(chain_verdict, groups=len(evidence)),
        note="a model-specific absolute comparison: our model and targets differ from the "
        "paper's (different bias per row), so absolute shares are expected to move; " + chance,
        value=float(np.mean(list(tvds.values()))),
        value_label="mean TVD, points",
        outside="model-specific: absolute shares of our model's and targets' rows against the "
        "paper's",
    )
