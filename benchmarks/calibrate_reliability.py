"""Calibration of the reliability ICC's interval on simulated studies with a known answer.

The design of issue #28: 50 simulated participants (:mod:`emogen.analysis.simulated_study`,
the participants of ``emogen study simulate``), 4 emotions, 2 identities, 3 repetitions. The
true ICC of each emotion is that of a 1000-participant, 4-repetition study of the same design
(its own sampling SD ≈ 0.02). Each of ``--studies`` studies gives one 95% jackknife interval per
emotion × identity (leave one participant out); the script prints the share that
covers the truth, per cell and pooled, with its binomial SE.

    EMOGEN_MODEL=… python -m benchmarks.calibrate_reliability --studies 100 [--seed 0]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from benchmarks.exact import share
from emogen.analysis.reliability import components, icc_interval
from emogen.analysis.simulated_study import PeopleDesign, simulate_people
from emogen.model.load import load_model


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--studies", type=int, default=100)
    ap.add_argument(
        "--seed",
        type=int,
        default=0,
        help="first study seed (0: the seeds of the docs' figures; another: a fresh-seed confirmation)",
    )
    args = ap.parse_args()
    rig = load_model(os.environ["EMOGEN_MODEL"]).rig
    t0 = time.perf_counter()
    big = simulate_people(
        PeopleDesign(
            participants=1000, repetitions=4, identities=("female-medium",), categorise=False
        ),
        rig,
        seed=999,
    )
    truth = {
        e: components(f[list(big.genes)].to_numpy(), f["participant_id"].to_numpy()).icc
        for e, f in big.faces.groupby("emotion")
    }
    print("true ICC (ED space):", {e: round(v, 3) for e, v in truth.items()})
    hits: dict[tuple[str, str], list[bool]] = {}
    widths = []
    for s in range(args.seed, args.seed + args.studies):
        sim = simulate_people(PeopleDesign(categorise=False), rig, seed=s)
        for (emotion, ident), f in sim.faces.groupby(["emotion", "identity"]):
            lo, hi = icc_interval(f[list(sim.genes)].to_numpy(), f["participant_id"].to_numpy())
            hits.setdefault((emotion, ident), []).append(lo <= truth[emotion] <= hi)
            widths.append(hi - lo)
    for cell, h in sorted(hits.items()):
        print(f"{cell[0]:>8} / {cell[1]:<14} covered {sum(h):3d} of {len(h)}")
    print(f"study seeds {args.seed}–{args.seed + args.studies - 1}")
    pooled = np.concatenate(list(hits.values()))
    se = np.sqrt(0.95 * 0.05 / len(pooled))
    print(
        f"pooled coverage {pooled.mean():.3f} of {len(pooled)} intervals (nominal 0.95, SE {se:.3f};"
        f" {share(int(pooled.sum()), len(pooled))});"
        f" median width {np.median(widths):.3f}; {time.perf_counter() - t0:.0f} s"
    )


if __name__ == "__main__":
    main()
