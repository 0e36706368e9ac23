"""Section IV-C: the initial target bias and the repeatability of the final faces, with fixed
sets and protocol initialisation (Table III)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from emogen.analysis import paper
from emogen.analysis.paper_targets import TARGET_1
from emogen.analysis.repeatability import BIN_LABELS, repeatability_bins
from emogen.analysis.replication.conditions import ConditionRunner, ConditionSpec
from emogen.analysis.replication.findings import Finding, graded

Row = tuple[str, int | None, str]  # (initialisation, fixed set, target)


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
    rows, shares, biases = [], {}, {}
    for init, option, tname, p_bias, p_bins in paper.TABLE_III:
        spec = ConditionSpec(init="fixed", fixed_option=option) if init == "fixed" else None
        s = runner.condition(f"{init} {option} {tname}", targets[tname], spec)
        b = repeatability_bins(s.final) * 100
        key = (init, option, tname)
        shares[key], biases[key] = b, float(s.best_initial.mean())
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
        findings=_findings(shares, biases),
    )


def _findings(shares: dict[Row, np.ndarray], biases: dict[Row, float]) -> list[Finding]:
    fixed_avg = min(biases[("fixed", 1, "average")], biases[("fixed", 3, "average")])
    prot_avg = biases[("protocol", None, "average")]
    fixed_keys = [k for k in shares if k[0] == "fixed"]
    prot_keys = [k for k in shares if k[0] == "protocol"]
    most = min(fixed_keys, key=lambda k: biases[k])
    first_fixed = shares[most][0]
    above_protocol = all(first_fixed > shares[k][0] for k in prot_keys)
    a, b = shares[("fixed", 1, "target 1")], shares[("fixed", 3, "target 1")]
    tvd = 0.5 * float(np.abs(a - b).sum())
    return [
        Finding(
            "Table III",
            "protocol initialisation hardly reaches a high bias: a fixed set can bias far more",
            "average target: 0.55 (protocol) vs 0.38 (fixed set 3)",
            f"average target: {prot_avg:.2f} (protocol) vs {fixed_avg:.2f} (best fixed set)",
            "holds" if fixed_avg < prot_avg else "differs",
            ""
            if fixed_avg < prot_avg
            else "our simulated participants build happy faces from the same "
            "building blocks that protocol initialisation draws its two happy faces from",
            rule="order: the best fixed set's bias below protocol's (average target)",
            value=prot_avg - fixed_avg,
            value_label="bias protocol − fixed",
        ),
        Finding(
            "Table III",
            "with a fixed set, a high bias piles the final faces into the first bin",
            "bias 0.38: 99% of pairs in [0, 0.25)",
            f"bias {biases[most]:.2f}: {first_fixed:.1f}% (protocol rows: "
            + ", ".join(f"{shares[k][0]:.1f}%" for k in prot_keys)
            + ")",
            graded(first_fixed >= 50 and above_protocol, above_protocol),
            rule="threshold: ≥ 50% in the first bin and above every protocol row; partly: the "
            "latter",
            value=float(first_fixed),
            value_label="first-bin % at the highest fixed bias",
        ),
        _sensitivity(shares, biases),
        Finding(
            "Table III",
            "initial complexity does not change repeatability at similar bias",
            "fixed sets 1 and 3, target 1: bins differ by 4.7 points (TVD)",
            f"bias {biases[('fixed', 1, 'target 1')]:.2f} and "
            f"{biases[('fixed', 3, 'target 1')]:.2f}: TVD {tvd:.1f} points",
            "holds" if tvd < 10 else "partly" if tvd < 20 else "differs",
            rule="threshold: TVD < 10 points holds, < 20 partly",
            value=tvd,
            value_label="TVD, points",
        ),
        _absolute(shares),
    ]


def _sensitivity(shares: dict[Row, np.ndarray], biases: dict[Row, float]) -> Finding:
    """Sensitivity to bias within ONE initialisation: the first bin's rise per unit of bias
    lost, from target 1 to the average target (no interpolation across fixed sets)."""

    def slope(init: str, option: int | None) -> float:
        lo, hi = (init, option, "target 1"), (init, option, "average")
        return float((shares[hi][0] - shares[lo][0]) / max(biases[lo] - biases[hi], 1e-9))

    prot = slope("protocol", None)
    fixed = {o: slope("fixed", o) for o in (1, 3)}
    less = [prot < f for f in fixed.values()]
    return Finding(
        "Table III",
        "protocol repeatability is less sensitive to bias: fewer identical results as bias grows",
        "first bin per unit bias: protocol (2.0 → 6.6%) / 0.19 = 24; fixed set 1 (1.0 → 29.8%) "
        "/ 0.43 = 67; set 3 (1.4 → 99%) / 0.49 = 199",
        f"first-bin points per unit bias: protocol {prot:.0f}; fixed set 1 {fixed[1]:.0f}, "
        f"set 3 {fixed[3]:.0f}",
        graded(all(less), any(less)),
        "each initialisation compared with itself (target 1 → average target); the earlier "
        "reading interpolated across different fixed sets",
        rule="order: protocol's slope below both fixed sets'; partly: below one",
        value=prot,
        value_label="protocol first-bin points per unit bias",
    )


def _absolute(shares: dict[Row, np.ndarray]) -> Finding:
    """Table III's bins themselves, row by row (TVD from the paper's)."""
    tvds = {
        (init, option, t): 0.5 * float(np.abs(shares[(init, option, t)] - np.array(bins)).sum())
        for init, option, t, _, bins in paper.TABLE_III
    }
    mean = float(np.mean(list(tvds.values())))
    return Finding(
        "Table III",
        "the repeatability bins themselves (absolute shares per row)",
        "six rows of bin shares",
        "TVD from the paper's row: "
        + ", ".join(
            f"{i} {o or ''} {t}: {v:.0f}".replace("  ", " ") for (i, o, t), v in tvds.items()
        )
        + " points",
        "holds" if mean < 10 else "partly" if mean < 20 else "differs",
        "our model and targets differ from the paper's (different bias per row): absolute "
        "shares are expected to move",
        rule="threshold: mean TVD over the rows < 10 points holds, < 20 partly",
        value=mean,
        value_label="mean TVD, points",
    )
