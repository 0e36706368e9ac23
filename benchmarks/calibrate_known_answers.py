"""How often the known answers of three single-seed analysis tests hold on a rig, over many
seeds: what a test's one seed stands for (tests/conftest.py; issue #41 item 7).

    python -m benchmarks.calibrate_known_answers [--seeds 40] [--first-seed 3000] [--rig PATH]

* ``own``: tests/analysis/test_categorisation_models.py — 60 participants label with their own
  prototypes: the primary contrast, GEE and two-stage t below 10⁻³, the control's p ≤ 0.02;
* ``gene``: tests/analysis/test_genes.py — a +0.6 group shift on browInnerUp (happy): max-T finds
  it, with the right sign, and rejects no sad cell (the sad prototypes are the same in both
  groups; happy cells may move with the shift: docs/analysis.md, knock-on effects);
* ``identity``: tests/analysis/test_identity.py — 50 participants × 4 emotions × 2 identities ×
  3 repetitions, a 0.6 identity shift on one gene of every emotion: the within- against
  between-identity test and its sign-flip p below 0.05, the right sign.

The designs were chosen on rig 3 over seeds 3000–3039 (20 participants for ``own`` held at 14
of 40 seeds, 40 at 35; 30 participants × 2 repetitions for ``identity`` at 27, 50 × 2 at 37);
the docs' figures are from other seeds (tests/conftest.py).

Prints each check's pass rate with its Clopper–Pearson 95% interval.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from typing import Any

import numpy as np

from benchmarks.calibrate_genes import NULL
from benchmarks.exact import share
from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people
from emogen.errors import EmoGenError

#: The tests' planted designs (imported by the tests, so the rates here are theirs).
OWN = PeopleDesign(participants=60, repetitions=2, identities=("female-medium",))
GENE = replace(NULL, shifts={"b": {"happy": {"browInnerUp": 0.6}}})
IDENTITY_SHIFT = {
    "male-medium": {
        "happy": {"browInnerUp": 0.6},
        "sad": {"mouthSmile": 0.6},
        "angry": {"jawOpen": 0.6},
        "fearful": {"noseSneer": 0.6},
    }
}
IDENTITY = PeopleDesign(
    participants=50, repetitions=3, categorise=False, identity_shifts=IDENTITY_SHIFT
)


def own(rig: Any, seed: int) -> bool:
    from emogen.analysis import categorisation_models as cm

    res = cm.own_distance(
        as_people(simulate_people(OWN, rig, seed=seed)),
        rng=np.random.default_rng(1),
        n_shuffles=99,
    )
    if not isinstance(res, cm.OwnDistance):
        return False  # too few participants: a one-line reason instead of a result
    return bool(
        res.primary["status"] == "ok"
        and res.primary["contrast"] < 0
        and res.primary["p_two_way"] < 1e-3
        and res.gee["contrast"] < 0
        and res.gee["p"] < 1e-3
        and res.two_stage["mean_contrast"] < 0
        and res.two_stage["p_t"] < 1e-3
        and res.control["p"] <= 0.02
    )


def gene(rig: Any, seed: int) -> bool:
    from emogen.analysis.genes import GeneTestOptions, group_gene_tests

    people = as_people(simulate_people(GENE, rig, seed=seed))
    g = group_gene_tests(people, GeneTestOptions(permutations=2000), rng=np.random.default_rng(0))
    hits = g[g["significant_maxt"]]
    found = hits[(hits["gene"] == "browInnerUp") & (hits["emotion"] == "happy")]
    return bool(
        len(found) == 1 and found["ci_high"].iloc[0] < 0 and not (hits["emotion"] == "sad").any()
    )


def identity(rig: Any, seed: int) -> bool:
    from emogen.analysis.identity import identity_distances, within_between_test

    people = as_people(simulate_people(IDENTITY, rig, seed=seed))
    r = within_between_test(identity_distances(people), rng=np.random.default_rng(0))
    return bool(
        r["difference"] > 0 and r["ci_low"] > 0 and r["p"] < 0.05 and r["p_sign_flip"] < 0.05
    )


CHECKS = {"own": own, "gene": gene, "identity": identity}


def main() -> None:
    import emogen

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--first-seed", type=int, default=3000)
    ap.add_argument("--rig", default=None, help="a rig TOML (default: the model's default rig)")
    ap.add_argument("--checks", nargs="+", choices=tuple(CHECKS), default=list(CHECKS))
    ap.add_argument("--model", default=None)
    a = ap.parse_args()
    if a.seeds < 1:
        ap.error(f"--seeds must be at least 1; got {a.seeds}")
    try:
        rig = emogen.load_model(a.model, rig=a.rig).rig
    except EmoGenError as err:
        ap.error(str(err))
    seeds = range(a.first_seed, a.first_seed + a.seeds)
    for name in a.checks:
        t0 = time.perf_counter()
        held = [s for s in seeds if CHECKS[name](rig, s)]
        failed = sorted(set(seeds) - set(held))
        print(
            f"{name}: held at {share(len(held), a.seeds)} seeds ({seeds.start}-{seeds.stop - 1}; "
            f"failed at {failed}) ({time.perf_counter() - t0:.0f} s)",
            flush=True,
        )


if __name__ == "__main__":
    main()
