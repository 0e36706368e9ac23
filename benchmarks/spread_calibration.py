"""Known-answer calibration of ``latent_spread_test`` as ``emogen analyse`` uses it.

Under H0 every face of a group evolved toward ONE shared target by choosers with choice noise
T; the test (its latent target fitted from the group's mean, as in analyse) must flag such a
group at a rate of at most α. K independent groups per cell: the flagged count is
Binomial(K, p), its share has standard error sqrt(α(1 − α)/K); a cell passes when the share is
≤ α + 2 SE. Power: groups whose participants each evolve their own target (the shared target
with every active gene scaled by 1 + N(0, sd), clipped at 0) must be flagged. Every group has
its own null simulation (seed), as every study's analysis has: groups sharing one null pool
would share its sampling error, and their flags would not be independent draws.

    python -m benchmarks.spread_calibration --groups 40 --sizes 20 80 240 --out grid.csv
    python -m benchmarks.spread_calibration --groups 60 --seed 41   # fresh seeds
    python -m benchmarks.spread_calibration --groups 20 --power-spread 0.2   # + power cells
    python -m benchmarks.spread_calibration --targets medium --sizes 80 \
        --temperatures 0.05 --assumed-temperatures 0 0.025 0.05 0.1   # sensitivity to T

Cells: sparse (one gene), medium (four genes) and dense (the happy face's building blocks)
targets × group sizes × T; G = 10 generations with the paper's selections. Group k of a cell
with seed S simulates from seeds 50,000 + 10,000·S + k (its faces) and 90,000 + 10,000·S + k
(its null); before #41 the null cells ignored ``--seed`` and always used S = 0.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
import pandas as pd

from benchmarks.exact import clopper_pearson

ALPHA = 0.05
TARGETS: dict[str, dict[str, float]] = {
    "sparse": {"jawOpen": 1.0},
    "medium": {"browInnerUp": 0.7, "eyeWide": 0.5, "jawOpen": 0.4, "mouthFrown": 0.3},
    "dense": {
        "mouthSmile": 0.9,
        "cheekRaiser": 0.7,
        "cheekSquint": 0.6,
        "eyeSquint": 0.45,
        "mouthDimple": 0.35,
        "mouthUpperUp": 0.3,
        "jawOpen": 0.25,
    },
}
#: the test's settings in a cell: analyse's defaults but smaller pools (a grid of many groups)
TEST_KW: dict[str, int] = {"draws": 400, "refine_runs": 200, "pool_runs": 400, "iterations": 2}


def group_faces(
    rig: object, target: np.ndarray, n: int, temperature: float, spread: float, seed: int
) -> np.ndarray:
    """n final faces: each participant's own target (``spread`` 0: the shared one) run once."""
    from emogen.analysis.elites import final_faces_simulator

    rng = np.random.default_rng(seed)
    owns = np.clip(target * (1 + spread * rng.standard_normal((n, *target.shape))), 0, None)
    sim = final_faces_simulator(_config(temperature), rig, seed * 1000)  # type: ignore[arg-type]
    return sim(owns, n)  # run i toward participant i's own target


def _config(temperature: float) -> object:
    from emogen.config import GAConfig, SimulationConfig

    return SimulationConfig(
        target={"jawOpen": 1.0}, ga=GAConfig(generations=10), noise_temperature=temperature
    )


def cell(
    rig: object,
    name: str,
    n: int,
    temperature: float,
    groups: int,
    spread: float = 0.0,
    seed: int = 0,
    assumed: float | None = None,
) -> dict[str, object]:
    """One cell of the grid: the share of ``groups`` groups flagged, with its SE. ``assumed``:
    the choice noise the test's null simulates (default: the groups' own T) — the test's
    sensitivity to a wrong assumption about T."""
    from emogen.analysis.elites import final_faces_simulator
    from emogen.analysis.noise import latent_spread_test

    target = np.asarray(rig.weights_from_names(TARGETS[name]), dtype=np.float64)  # type: ignore[attr-defined]
    t_null = temperature if assumed is None else assumed
    flagged, excess, covered = [], [], []
    t0 = time.perf_counter()
    for k in range(groups):
        s = seed * 10_000 + k
        if spread > 0:
            faces = group_faces(rig, target, n, temperature, spread, s)
        else:  # one shared target: n runs of one simulator (each run its own generator)
            faces = final_faces_simulator(_config(temperature), rig, 50_000 + s)(target, n)  # type: ignore[arg-type]
        # each group its own null simulation, as each study's analysis has (a shared one makes
        # the groups' verdicts correlated and the binomial SE wrong)
        null = final_faces_simulator(_config(t_null), rig, 90_000 + s)  # type: ignore[arg-type]
        test, _ = latent_spread_test(faces, null, rng=np.random.default_rng(s), **TEST_KW)  # type: ignore[arg-type]
        flagged.append(test.exceeds)
        excess.append(test.excess)
        covered.append(test.excess_lo <= 0 <= test.excess_hi)
    rate = float(np.mean(flagged))
    se = float(np.sqrt(ALPHA * (1 - ALPHA) / groups))
    lo, hi = clopper_pearson(int(np.sum(flagged)), groups)
    return {
        "target": name,
        "n": n,
        "T": temperature,
        "assumed T": t_null,
        "participant spread": spread,
        "groups": groups,
        "flagged": rate,
        "Clopper-Pearson 95%": f"[{lo:.3f}, {hi:.3f}]",
        "SE at α": se,
        "within α + 2 SE": rate <= ALPHA + 2 * se if spread == 0 else None,
        "mean excess spread": float(np.mean(excess)),
        "excess CI covers 0": float(np.mean(covered)),
        "seconds": time.perf_counter() - t0,
    }


def main() -> None:
    import emogen

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--groups", type=int, default=40)
    ap.add_argument("--sizes", type=int, nargs="+", default=[20, 80, 240])
    ap.add_argument("--targets", nargs="+", default=list(TARGETS))
    ap.add_argument("--temperatures", type=float, nargs="+", default=[0.05])
    ap.add_argument("--power-spread", type=float, default=0.0)
    ap.add_argument(
        "--assumed-temperatures",
        type=float,
        nargs="+",
        default=None,
        help="choice noise the null assumes (default: each cell's own T)",
    )
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument(
        "--seed",
        type=int,
        default=0,
        help="null cells' seed (power cells: seed + 1); 0: the rig-2 figures, another: fresh",
    )
    a = ap.parse_args()
    rig = emogen.load_model(os.environ["EMOGEN_MODEL"]).rig
    rows = []
    for name in a.targets:
        for n in a.sizes:
            for t in a.temperatures:
                for assumed in a.assumed_temperatures or [None]:
                    rows.append(cell(rig, name, n, t, a.groups, seed=a.seed, assumed=assumed))
                    print(pd.DataFrame(rows[-1:]).to_string(index=False), flush=True)
                if a.power_spread > 0:
                    rows.append(cell(rig, name, n, t, a.groups, a.power_spread, seed=a.seed + 1))
                    print(pd.DataFrame(rows[-1:]).to_string(index=False), flush=True)
    table = pd.DataFrame(rows)
    print(table.to_string(index=False))
    if a.out:
        table.to_csv(a.out, index=False)


if __name__ == "__main__":
    main()
