"""Known-answer calibration of perceptive-field clustering and identity effects over simulated
studies (:mod:`emogen.analysis.simulated_study`).

Per study (50 participants × 4 emotions × 2 identities × 3 repetitions unless changed):

* ``groups``: two planted subpopulations (group b's prototypes moved on two genes absent from
  each emotion, by ``--shift``) → share of studies with "structure", and the adjusted Rand
  index of the clusters against the planted groups;
* ``one``: one population → share of studies with "no structure" (its complement, the false
  structure rate, should be ≤ α + 2 SE);
* ``identity-null``: no identity shift → rejection rate of the within- vs between-identity test
  (≤ α + 2 SE, SE = √(α(1−α)/K)); ``identity-shift``: planted identity shifts → power;
* decoding: cross-identity decoding accuracy and its permutation chance on ``identity-null``.

    python -m benchmarks.calibrate_fields --studies 100
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.exact import share as exact_share

ALPHA = 0.05
GROUP_SHIFT = {
    "happy": ("browInnerUp", "mouthFrown"),
    "sad": ("mouthSmile", "jawOpen"),
    "angry": ("browInnerUp", "mouthSmile"),
    "fearful": ("mouthSmile", "noseSneer"),
}
IDENTITY_SHIFT = {
    "happy": ("browInnerUp",),
    "sad": ("mouthSmile",),
    "angry": ("jawOpen",),
    "fearful": ("noseSneer",),
}


def shifts(genes: dict[str, tuple[str, ...]], amount: float) -> dict[str, dict[str, float]]:
    return {e: {g: amount for g in gs} for e, gs in genes.items()}


def run(args: argparse.Namespace) -> None:
    from sklearn.metrics import adjusted_rand_score

    import emogen
    from emogen.analysis.field_clusters import cluster_fields
    from emogen.analysis.fields import perceptive_fields
    from emogen.analysis.identity import (
        cross_identity_decoding,
        identity_distances,
        within_between_test,
    )
    from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people
    from emogen.tasks.simulated import SimulatedDesign

    rig = emogen.load_model(args.model).rig
    who = SimulatedDesign(spread=args.spread)
    base = dict(participants=args.participants, categorise=False, participant=who)
    grouped = PeopleDesign(
        **base,
        groups=("a", "b"),  # type: ignore[arg-type]
        shifts={"b": shifts(GROUP_SHIFT, args.shift)},
    )
    one = PeopleDesign(**base)  # type: ignore[arg-type]
    ident = PeopleDesign(
        **base,
        identity_shifts={  # type: ignore[arg-type]
            "male-medium": shifts(IDENTITY_SHIFT, args.identity_shift)
        },
    )
    k = args.studies
    found, aris, false_structure, fp, power, cross, chance = [], [], [], [], [], [], []
    t0 = time.time()
    for s in range(args.seed, args.seed + k):
        rng = np.random.default_rng(10_000 + s)
        sim = simulate_people(grouped, rig, seed=s)
        c = cluster_fields(perceptive_fields(as_people(sim)), rng=rng, n_null=args.null)
        found.append(c.structure)
        aris.append(adjusted_rand_score(sim.group, c.labels) if c.structure else 0.0)
        sim = simulate_people(one, rig, seed=50_000 + s)
        people = as_people(sim)
        false_structure.append(
            cluster_fields(perceptive_fields(people), rng=rng, n_null=args.null).structure
        )
        fp.append(within_between_test(identity_distances(people), rng=rng)["p"] < ALPHA)
        if s - args.seed < args.decoding_studies:
            dec = cross_identity_decoding(people, rng=rng, n_perm=args.perm)
            cross += dec.loc[dec["cross"], "accuracy"].tolist()
            chance += dec.loc[dec["cross"], "chance"].tolist()
        sim = simulate_people(ident, rig, seed=90_000 + s)
        power.append(within_between_test(identity_distances(as_people(sim)), rng=rng)["p"] < ALPHA)
        print(f"study {s - args.seed + 1}/{k} ({time.time() - t0:.0f} s)", flush=True)
    se = np.sqrt(ALPHA * (1 - ALPHA) / k)

    def share(x: list[bool]) -> str:
        p = float(np.mean(x))
        return f"{p:.3f} (SE {np.sqrt(p * (1 - p) / k):.3f}; {exact_share(int(sum(x)), k)})"

    print(
        f"\n{k} studies per cell, {args.participants} participants, spread {args.spread}, "
        f"null studies per clustering test {args.null}"
    )
    print(
        f"two planted groups: structure found {share(found)}; ARI mean {np.mean(aris):.3f}, "
        f"median {np.median(aris):.3f} (0 where no structure)"
    )
    print(
        f"one population: no structure {share([not f for f in false_structure])}; false "
        f"structure {share(false_structure)} (bound α + 2 SE = {ALPHA + 2 * se:.3f})"
    )
    print(f"identity, no shift: false-positive rate {share(fp)} (bound {ALPHA + 2 * se:.3f})")
    print(f"identity, shift {args.identity_shift}: power {share(power)}")
    print(
        f"cross-identity decoding ({len(cross)} directions): accuracy mean {np.mean(cross):.3f}"
        f" (min {np.min(cross):.3f}), permutation chance mean {np.mean(chance):.3f}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--studies", type=int, default=100)
    ap.add_argument("--participants", type=int, default=50)
    ap.add_argument("--spread", type=float, default=0.15)
    ap.add_argument("--shift", type=float, default=0.6)
    ap.add_argument("--identity-shift", type=float, default=0.6)
    ap.add_argument("--null", type=int, default=39, help="one-population studies per test")
    ap.add_argument("--perm", type=int, default=49, help="permutations per decoding")
    ap.add_argument("--decoding-studies", type=int, default=10)
    ap.add_argument("--model", default=None)
    ap.add_argument(
        "--seed",
        type=int,
        default=0,
        help="first study seed (0: the docs' figures; another: fresh)",
    )
    run(ap.parse_args())


if __name__ == "__main__":
    main()
