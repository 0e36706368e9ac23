"""The timing test of dynamic evolve blocks (:mod:`emogen.tasks.evolve.dynamic_analysis`) on
simulated dynamic studies with a known answer: participants of ``emogen study simulate``
(:mod:`emogen.tasks.simulated`) evolve dynamic faces through the real study service and
database; the study is exported and analysed as ``emogen analyse`` does.

    nice -n 10 python benchmarks/calibrate_timing.py --studies 20 --condition null
    nice -n 10 python benchmarks/calibrate_timing.py --studies 1 --condition planted

Conditions: ``null`` (one time course shared by the emotions: the test should reject at α),
``planted`` (fearful peaks at 0.2 of the clip, sad at 0.7). The study: examples/dynamic.toml's
dynamic block alone, emotions sad and fearful, ``--generations`` generations (16: in 8 the GA
moves the genes' timing too little for 30 participants to show the planted difference, p 0.07).
Study s has seed ``--first-seed`` + s. Prints per study its seed and test, then the rejection
rate at α with its exact (Clopper–Pearson) 95% interval and the rig the faces were made on.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import binomtest

from emogen.model import load_model
from emogen.model.face import FaceModel
from emogen.study.config import load_study_config
from emogen.study.export import export_tables
from emogen.study.simulate import SimulationPlan, simulate_study
from emogen.study.storage import Store
from emogen.tasks.evolve.dynamic_analysis import (
    TimingTest,
    final_curves,
    participant_timing,
    timing_test,
)
from emogen.tasks.simulated import SimulatedDesign

ROOT = Path(__file__).resolve().parents[1]
PLANTED = {"fearful": 0.2, "sad": 0.7}


def record_timing_study(
    folder: Path,
    *,
    participants: int,
    seed: int,
    peak_at: dict[str, float],
    generations: int = 16,
    model: FaceModel | None = None,
) -> str:
    """One simulated dynamic study recorded in a database under ``folder``; its URL. Faces are
    uncorrected (``correct = false``): the timing analysis reads the genes' curves, which
    correction leaves as they are, and a step is several times cheaper."""
    study = load_study_config(ROOT / "examples" / "dynamic.toml")
    ga = study.ga.model_copy(update={"generations": generations})
    study = study.model_copy(
        update={
            "blocks": study.blocks[:1],
            "emotions": ("sad", "fearful"),
            "ga": ga,
            "correct": False,
        }
    )
    url = f"sqlite:///{folder / f'timing-{seed}.sqlite'}"
    plan = SimulationPlan(
        config=study,
        database_url=url,
        seed=seed,
        participants=participants,
        design=SimulatedDesign(peak_at=peak_at),
        shuffle_prototypes=False,
    )
    simulate_study(plan, model=model)
    return url


def timing_study(
    folder: Path, *, alpha: float = 0.05, **design: Any
) -> tuple[TimingTest | None, pd.DataFrame]:
    """One simulated dynamic study (:func:`record_timing_study` with ``design``), exported and
    tested; the test and the participants' timing."""
    url = record_timing_study(folder, **design)
    store = Store(url)
    try:
        tables = export_tables(store)
    finally:
        store.dispose()
    curves = final_curves(tables["final_faces"], tables["face_curves"])
    timing = participant_timing(curves)
    rng = np.random.default_rng(design["seed"])
    return timing_test(timing, str(timing["block_name"].iloc[0]), rng, alpha), timing


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """The exact (Clopper–Pearson) interval of a rate k / n (scipy's ``binomtest``)."""
    ci = binomtest(k, n).proportion_ci(confidence_level=level, method="exact")
    return float(ci.low), float(ci.high)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--studies", type=int, default=20)
    parser.add_argument("--participants", type=int, default=30)
    parser.add_argument("--generations", type=int, default=16)
    parser.add_argument("--condition", choices=["null", "planted"], default="null")
    parser.add_argument("--alpha", type=float, default=0.05)
    parser.add_argument("--first-seed", type=int, default=1000, help="Study s has seed first + s.")
    parser.add_argument("--model", type=Path, default=None)
    args = parser.parse_args()
    peak_at = PLANTED if args.condition == "planted" else {}
    rejected = tested = 0
    started = time.perf_counter()
    model = load_model(args.model)
    with tempfile.TemporaryDirectory() as tmp:
        for s in range(args.studies):
            test, timing = timing_study(
                Path(tmp),
                participants=args.participants,
                seed=args.first_seed + s,
                peak_at=peak_at,
                generations=args.generations,
                model=model,
                alpha=args.alpha,
            )
            if test is None:
                print(
                    f"study {s} (seed {args.first_seed + s}): no test (too few participants with both emotions)"
                )
                continue
            tested += 1
            rejected += test.p_value < args.alpha
            peaks = timing.groupby("emotion")["peak_s"].mean().round(3).to_dict()
            print(
                f"study {s} (seed {args.first_seed + s}): mean peak latency (s) {peaks}; n={test.n_participants} F={test.f:.2f} p={test.p_value:.4f} "
                f"eta2={test.eta2:.3f} [{test.eta2_low:.3f}, {test.eta2_high:.3f}]",
                flush=True,
            )
    lo, hi = clopper_pearson(rejected, tested) if tested else (float("nan"), float("nan"))
    print(
        f"{args.condition} on {model.rig.name}, seeds {args.first_seed}-"
        f"{args.first_seed + args.studies - 1}: rejected {rejected}/{tested} at alpha "
        f"{args.alpha} ({rejected / max(tested, 1):.3f}, Clopper-Pearson 95% [{lo:.3f}, "
        f"{hi:.3f}]); {time.perf_counter() - started:.0f} s"
    )


if __name__ == "__main__":
    main()
