"""Known answers of the spread test's empirical null (``emogen.analysis.noise_empirical``: the
between-participant spread of repeated faces against their within-participant spread, with a
permutation p over participants), run as ``emogen analyse`` runs it (999 permutations,
α = 0.05, the jackknife interval of the excess σ²_b), on simulated studies with repetitions.

    python benchmarks/calibrate_empirical_null.py                          # the docs' grid
    python benchmarks/calibrate_empirical_null.py --spreads 0 --sizes 20 --studies 200 --seed 410000

Each study (``emogen.analysis.simulated_study``, on the model's default rig): one identity
(female-medium), happy and sad, ``--repetitions`` faces per participant and emotion, the
participants' own prototypes drawn with SD ``spread`` per gene around the population's
(spread 0: one shared prototype, the null). One test per emotion; K tests per cell = studies ×
2. Under the null a test is flagged with probability at most α, so the flagged share has SE
sqrt(α(1 − α)/K): a cell passes when it is at most α + 2 SE. Prints per cell the flagged
count, its share with the Wilson 95% interval and the exact (Clopper–Pearson) one, the bound,
and how often the excess interval covered 0. The two emotions of one study share its
participants (their GA runs and prototypes are drawn independently), so the cell's studies
are printed too. ``--seed``: the first study's seed; a cell's seeds are fixed by its spread
and size (``seed + 1000 × size + 100 000 × spread index``), not by which other cells run.
Model: ``$EMOGEN_MODEL``, else ``../shared/ict-facekit/FaceXModel``; ``--rig``: a rig TOML
(``src/emogen/data/ict_rig_2.toml`` for rig 2), else the default rig.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
from scipy import stats

from benchmarks.calibrate_planted import wilson

ALPHA = 0.05
EMOTIONS = ("happy", "sad")
SPREADS = (0.0, 0.05, 0.1, 0.2, 0.5)


def one_study(rig: object, spread: float, n: int, repetitions: int, seed: int) -> list[tuple]:
    """(flagged, excess interval covers 0) of each emotion's test in one simulated study."""
    from emogen.analysis.noise_empirical import empirical_spread_test
    from emogen.analysis.simulated_study import PeopleDesign, simulate_people
    from emogen.tasks.simulated import SimulatedDesign

    design = PeopleDesign(
        emotions=EMOTIONS,
        identities=("female-medium",),
        participants=n,
        repetitions=repetitions,
        participant=SimulatedDesign(spread=spread),
        categorise=False,
    )
    sim = simulate_people(design, rig, seed=seed)  # type: ignore[arg-type]
    rng = np.random.default_rng(seed)
    out = []
    for emotion in EMOTIONS:
        f = sim.faces[sim.faces["emotion"] == emotion]
        res = empirical_spread_test(
            f[list(sim.weights)].to_numpy(),
            f["participant_id"].to_numpy(),
            group=emotion,
            alpha=ALPHA,
            permutations=999,
            rng=rng,
        )
        out.append((res.exceeds, res.excess_lo <= 0 <= res.excess_hi))
    return out


def clopper_pearson(k: int, n: int) -> tuple[float, float]:
    lo = 0.0 if k == 0 else float(stats.beta.ppf(0.025, k, n - k + 1))
    hi = 1.0 if k == n else float(stats.beta.ppf(0.975, k + 1, n - k))
    return lo, hi


def cell_line(spread: float, n: int, results: list[list[tuple]], sec: float) -> str:
    tests = [t for study in results for t in study]
    k, big_k = sum(f for f, _ in tests), len(tests)
    studies = sum(any(f for f, _ in study) for study in results)
    wl, wh = wilson(k, big_k)
    cl, ch = clopper_pearson(k, big_k)
    line = (
        f"spread {spread:g}, n = {n}: flagged {k} of {big_k} tests = {k / big_k:.3f} "
        f"(Wilson 95% [{wl:.3f}, {wh:.3f}]; Clopper–Pearson [{cl:.3f}, {ch:.3f}])"
    )
    if spread == 0:
        bound = ALPHA + 2 * np.sqrt(ALPHA * (1 - ALPHA) / big_k)
        covers = np.mean([c for _, c in tests])
        verdict = "within" if k / big_k <= bound else "ABOVE"
        line += f"; bound α + 2 SE = {bound:.3f} ({verdict}); interval covers 0 in {covers:.1%}"
    return line + f"; studies with a flag: {studies} of {len(results)} ({sec:.0f} s)"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spreads", type=float, nargs="+", default=list(SPREADS))
    ap.add_argument("--sizes", type=int, nargs="+", default=[20, 80])
    ap.add_argument("--studies", type=int, default=100, help="simulated studies per cell")
    ap.add_argument("--repetitions", type=int, default=3)
    ap.add_argument("--seed", type=int, default=410_000)
    ap.add_argument("--model", type=Path, default=None)
    ap.add_argument("--rig", type=Path, default=None, help="a rig TOML (default: the packaged one)")
    args = ap.parse_args()
    import emogen

    model = args.model or Path(os.environ.get("EMOGEN_MODEL", "../shared/ict-facekit/FaceXModel"))
    rig = emogen.load_model(model, rig=args.rig).rig
    print(
        f"empirical null on rig {args.rig or 'ict_rig.toml (the default)'}: "
        f"{args.studies} studies per cell, {args.repetitions} repetitions, "
        f"emotions {', '.join(EMOTIONS)}, 999 permutations, α = {ALPHA}, first seed {args.seed}"
    )
    for spread in args.spreads:
        s_index = SPREADS.index(spread) if spread in SPREADS else len(SPREADS)
        for n in args.sizes:
            first = args.seed + 1000 * n + 100_000 * s_index
            start = time.perf_counter()
            results = [
                one_study(rig, spread, n, args.repetitions, first + s) for s in range(args.studies)
            ]
            print(cell_line(spread, n, results, time.perf_counter() - start), flush=True)


if __name__ == "__main__":
    main()
