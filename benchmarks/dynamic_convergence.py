"""Convergence to a dynamic target (docs/ga.md, "Simulated observers of dynamic faces").

Runs what ``emogen simulate --dynamic`` runs — the dynamic simulation, the same with the timing
held at the target's, and the static simulation of the target's peak profile, one seed — and
prints, per run kind and part, the elite error at generation 0 and G (mean ± sd over runs), the
largest gap between held timing's and the static run's mean peak error over the generations
beside three standard errors of that difference (the tolerance of
tests/simulate/test_dynamic.py), the same target moving as one curve (held timing then makes
the static run's choices exactly), and the timing part after ``--long`` generations. With
``--figure`` it draws the G-generation comparison (docs/images/dynamic_convergence.png).

``python benchmarks/dynamic_convergence.py [--runs 500] [--seed 1] [--long 30] [--figure PATH]``
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from emogen.config import SimulationConfig
from emogen.simulate.convergence import compare_dynamic, convergence_table
from emogen.simulate.runner import run_simulation

#: The three-shape analogue of Table V's target that bench_simulate.py uses (jawOpen; noseSneer,
#: a pair; the paper's three-shape target ends at 0.267 ± 0.100), given a time course: the
#: nose wrinkles first and holds, the jaw drops later and briefly. Timing: [onset,
#: acceleration, peak, deceleration, offset], each in [0, 1].
TARGET = {"jawOpen": 1.0, "noseSneer": 0.6}
TIMING = {
    "noseSneer": [0.05, 0.3, 0.3, 0.5, 0.7],
    "jawOpen": [0.4, 0.6, 0.3, 0.4, 0.3],
}
#: The command the docs show (the CLI prints the same numbers).
COMMAND = (
    "emogen simulate --dynamic -o out/dynamic --runs {runs} --seed {seed} "
    + " ".join(f"-t {k}={v}" for k, v in TARGET.items())
    + " "
    + " ".join(f"--target-timing {k}=" + ",".join(map(str, v)) for k, v in TIMING.items())
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=500)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--long", type=int, default=30, help="generations of the long run")
    parser.add_argument("--figure", type=Path, default=None)
    args = parser.parse_args()
    from benchmarks.run import model_path
    from emogen.model import load_model

    model = load_model(model_path())
    print(COMMAND.format(runs=args.runs, seed=args.seed))
    cfg = SimulationConfig(
        target=TARGET, runs=args.runs, seed=args.seed, dynamic={"timing": TIMING}
    )
    start = time.perf_counter()
    table = convergence_table(compare_dynamic(cfg, model.rig))
    print(f"three simulations of {args.runs} runs: {time.perf_counter() - start:.1f} s")
    g_last = int(table["generation"].max())
    for (kind, part), rows in table.groupby(["run_kind", "part"], sort=False):
        first, last = rows.iloc[0], rows.iloc[-1]
        print(
            f"  {kind:<12} {part:<19} g0 {first['mean']:.3f} ± {first['sd']:.3f}   "
            f"g{g_last} {last['mean']:.3f} ± {last['sd']:.3f}   (runs {int(last['runs'])})"
        )
    peak = table[table["part"] == "elite_peak_error"].pivot(
        index="generation", columns="run_kind", values=["mean", "sd"]
    )
    gap = (peak["mean"]["held_timing"] - peak["mean"]["static"]).abs()
    se = np.sqrt((peak["sd"]["held_timing"] ** 2 + peak["sd"]["static"] ** 2) / args.runs)
    free_gap = peak["mean"]["dynamic"].iloc[-1] - peak["mean"]["static"].iloc[-1]
    print(
        f"held timing vs static, mean peak error: largest gap {gap.max():.4f} (generation "
        f"{int(gap.idxmax())}); 3 standard errors there {3 * se[gap.idxmax()]:.4f}; "
        f"free timing's gap at g{g_last}: {free_gap:.4f}"
    )
    one_curve = {key: [0.2, 0.4, 0.3, 0.6, 0.5] for key in TARGET}
    held = SimulationConfig(
        target=TARGET,
        runs=args.runs,
        seed=args.seed,
        dynamic={"timing": one_curve, "hold_timing": True},
    )
    a = run_simulation(held, model.rig).table["elite_error"].to_numpy()
    b = run_simulation(held.model_copy(update={"dynamic": None}), model.rig).table
    diff = float(np.max(np.abs(a - b["elite_error"].to_numpy())))
    print(f"target moving as one curve, held timing vs static: largest |Δ elite error| {diff:.2e}")
    long = cfg.model_copy(update={"ga": cfg.ga.model_copy(update={"generations": args.long})})
    long_table = run_simulation(long, model.rig).table
    stats = long_table.groupby("generation")["elite_timing_error"].agg(["mean", "std"])
    marks = sorted({0, 10, args.long // 2, args.long})
    print(
        f"dynamic, {args.long} generations, timing part (s): "
        + ", ".join(f"g{g} {stats['mean'][g]:.3f} ± {stats['std'][g]:.3f}" for g in marks)
    )
    if args.figure is not None:
        from emogen.analysis.plots import formats
        from emogen.cli.simulate_dynamic import convergence_figure

        with formats(["png"]):
            path = convergence_figure(
                table, args.figure, title=f"{args.runs} runs, seed {args.seed}: {', '.join(TARGET)}"
            )
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
