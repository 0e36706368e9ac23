"""The power analysis's assumptions made visible: the required n over participant spread × T.

The replication's power analysis (two happy groups differing by browInnerUp 0.4, one face per
participant, CD statistic) assumes a participant spread of 0.1 per gene and choice noise
T = 0.05. This grid reruns it over both: each cell is a full simulated power curve (fresh
participants per experiment), its required n for 80% power with the 95% interval and the
method (the logistic fit where it fits the simulated points, else interpolation;
:mod:`emogen.analysis.power_required`), and the false-positive rate on null experiments.

    EMOGEN_MODEL=… python -m benchmarks.power_sensitivity --sds 0.05 0.1 0.2 \
        --temperatures 0.02 0.05 0.1 --replicates 100 --out grid.csv --figure grid.png
    python -m benchmarks.power_sensitivity --sds 0.1 --temperatures 0.05 --blunted 0.7

``--blunted`` asks the intensity question (blunted expressions): group B's happy face at a
lower intensity, which the CD statistic cannot see; the test then uses ``statistic="ed"``.
``--observer ed`` makes the simulated participants choose by ED too: a CD chooser ignores the
intensity of its own prototype, so its faces carry none of the effect.
"""

from __future__ import annotations

import argparse
import os
import time
from itertools import product
from pathlib import Path

import numpy as np
import pandas as pd

from emogen.analysis.power import PowerResult
from emogen.model.rig import Rig


def blunted_power(
    rig: Rig, scale: float, sd: float, temperature: float, a: argparse.Namespace
) -> PowerResult:
    """Group B's happy face is group A's at ``scale`` intensity (blunted): CD cannot see it, so
    the test compares the groups' mean faces by Euclidean distance (``statistic="ed"``)."""
    from emogen.analysis.paper_targets import HAPPY
    from emogen.analysis.power import GroupSampler, power_analysis
    from emogen.config import SimulationConfig

    w = np.asarray(rig.weights_from_names(dict(HAPPY)), dtype=np.float64)
    cfg = SimulationConfig.model_validate(
        {"target": dict(HAPPY), "noise_temperature": temperature, "metric": a.observer}
    )
    a_, b_ = (GroupSampler(cfg, rig, p, a.seed + k, sd) for k, p in enumerate((w, scale * w)))
    return power_analysis(
        a_,
        b_,
        max_n=a.max_n,
        replicates=a.replicates,
        permutations=a.permutations,
        statistic="ed",
        seed=a.seed,
    )


def cell(rig: Rig, sd: float, temperature: float, a: argparse.Namespace) -> dict[str, object]:
    """One cell: the power curve at participant spread ``sd`` and choice noise ``temperature``
    (browInnerUp added, CD statistic; or with ``--blunted`` a weaker happy face, ED)."""
    from emogen.analysis.replication.analysis_tools import brow_power

    t0 = time.perf_counter()
    if a.blunted:
        res = blunted_power(rig, a.blunted, sd, temperature, a)
    else:
        _, res = brow_power(
            rig,
            participant_sd=sd,
            temperature=temperature,
            seed=a.seed,
            max_n=a.max_n,
            replicates=a.replicates,
            permutations=a.permutations,
        )
    req = res.required
    if req is None:
        raise RuntimeError("power_analysis did not read a required n")
    row: dict[str, object] = {
        "difference": f"happy ×{a.blunted} (ED test, {a.observer} observer)"
        if a.blunted
        else "browInnerUp 0.4 (CD)",
        "participant sd": sd,
        "T": temperature,
        "n required": req.n,
        "ci low": req.lo,
        "ci high": req.hi,
        "method": req.method,
        "fit chi2 p": req.fit_p,
        "smallest simulated n at 80%": res.n_observed,
        "max false positive": res.max_false_positive,
        "points": len(res.curve),
        "seconds": time.perf_counter() - t0,
    }
    print(pd.DataFrame([row]).to_string(index=False), flush=True)
    return row


def figure(table: pd.DataFrame, path: Path) -> None:
    """Required n against T, one line per participant spread, with the 95% intervals."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for sd, rows in table.groupby("participant sd"):
        rows = rows.sort_values("T")
        n = rows["n required"].astype(float)
        lo = n - rows["ci low"].astype(float)
        hi = rows["ci high"].astype(float).fillna(rows["n required"].max() * 1.5) - n
        ax.errorbar(rows["T"], n, yerr=[lo, hi], marker="o", capsize=3, label=f"spread {sd}")
    ax.set_xlabel("choice noise T (CD units)")
    ax.set_ylabel("participants per group for 80% power")
    ax.set_yscale("log")
    ax.legend(frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    import emogen

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sds", type=float, nargs="+", default=[0.05, 0.1, 0.2])
    ap.add_argument("--temperatures", type=float, nargs="+", default=[0.02, 0.05, 0.1])
    ap.add_argument("--replicates", type=int, default=100)
    ap.add_argument("--permutations", type=int, default=100)
    ap.add_argument("--max-n", type=int, default=160)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--figure", type=Path, default=None)
    ap.add_argument(
        "--blunted",
        type=float,
        default=0.0,
        help="group B = group A's happy face at this intensity, tested by ED (0: browInnerUp, CD)",
    )
    ap.add_argument(
        "--observer",
        default="cd",
        choices=["cd", "ed"],
        help="the simulated participants' choice metric with --blunted (cd is blind to intensity)",
    )
    a = ap.parse_args()
    rig = emogen.load_model(os.environ["EMOGEN_MODEL"]).rig
    cells = product(a.sds, a.temperatures)
    table = pd.DataFrame([cell(rig, sd, t, a) for sd, t in cells])
    print(table.to_string(index=False))
    if a.out:
        table.to_csv(a.out, index=False)
    if a.figure:
        figure(table, a.figure)


if __name__ == "__main__":
    main()
