"""Calibration of the own-distance categorisation model (emogen.analysis.categorisation_models):
how often each of its tests finds the effect when simulated participants label with their own
prototypes, and how often it falsely finds it when they label with another participant's
(``shuffle_prototypes``), over many simulated studies.

    python -m benchmarks.calibrate_categorisation            # 100 studies each, 50 participants
    python -m benchmarks.calibrate_categorisation --studies 20 --participants 30
    python -m benchmarks.calibrate_categorisation --seed 41000 --studies 200 --conditions null

Seeds: study s of the effect condition is ``--seed + s``, of the null ``--seed + 1000 + s``
(2028: the figures before #41; a fresh-seed confirmation takes another).

Prints one line per study and, per condition and test, the rejection rate at α with its binomial
SE and exact (Clopper–Pearson) interval; for the shuffled condition, the bound
α + 2·SE(α) = α + 2·sqrt(α(1 − α)/studies).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.exact import share

TESTS = (
    ("primary", "p"),
    ("gee", "p"),
    ("two_stage", "p_t"),
    ("two_stage", "p_wilcoxon"),
    ("control", "p"),
)


def main() -> None:
    import emogen
    from emogen.analysis.categorisation_models import OwnDistance, own_distance
    from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--studies", type=int, default=100)
    ap.add_argument("--participants", type=int, default=50)
    ap.add_argument("--shuffles", type=int, default=99)
    ap.add_argument("--alpha", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=2028)
    ap.add_argument("--conditions", choices=("both", "null", "effect"), default="both")
    args = ap.parse_args()
    rig = emogen.load_model().rig
    chosen = {"both": (False, True), "null": (True,), "effect": (False,)}[args.conditions]
    for shuffle in chosen:
        design = PeopleDesign(participants=args.participants, shuffle_prototypes=shuffle)
        p = np.full((args.studies, len(TESTS)), np.nan)
        start = time.perf_counter()
        for s in range(args.studies):
            seed = args.seed + 1000 * shuffle + s
            people = as_people(simulate_people(design, rig, seed=seed))
            res = own_distance(people, rng=np.random.default_rng(seed), n_shuffles=args.shuffles)
            if not isinstance(res, OwnDistance):
                raise SystemExit(f"study {s}: {res}")
            p[s] = [_p(getattr(res, part)[key]) for part, key in TESTS]
            g = res.primary
            fit = (
                f"primary contrast {g['contrast']:+.2f} (SE {g['se_contrast']:.2f})"
                if g["status"] == "ok"
                else f"primary not estimated ({g['reason']})"
            )
            print(
                f"shuffle={shuffle} study {s}: {fit}; p: "
                + ", ".join(
                    f"{part} {key} {v:.3f}" for (part, key), v in zip(TESTS, p[s], strict=True)
                ),
                flush=True,
            )
        report(shuffle, p, args, time.perf_counter() - start)


def _p(value: float | None) -> float:
    """A test's p; a fit without an estimate (None) counts as not rejecting."""
    return 1.0 if value is None else float(value)


def report(shuffle: bool, p: np.ndarray, args: argparse.Namespace, seconds: float) -> None:
    n, a = len(p), args.alpha
    bound = a + 2 * np.sqrt(a * (1 - a) / n)
    what = "shuffled prototypes (null)" if shuffle else "own prototypes (effect present)"
    print(
        f"\n== {what}: {n} studies × {args.participants} participants, α = {a}, {seconds:.0f} s =="
    )
    for k, (part, key) in enumerate(TESTS):
        hits = int(np.sum(p[:, k] <= a))
        rate = hits / n
        se = np.sqrt(rate * (1 - rate) / n)
        verdict = ("≤ bound" if rate <= bound else "ABOVE bound") if shuffle else ""
        print(
            f"  {part:9s} {key:10s} rejection rate {rate:.3f} (SE {se:.3f}; {share(hits, n)}) "
            f"{f'bound {bound:.3f} ' if shuffle else ''}{verdict}"
        )


if __name__ == "__main__":
    main()
