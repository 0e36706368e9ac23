"""Calibration of the per-gene and condition tests of #28 (items 5–6) over 100 simulated
studies each; prints the figures reported in docs/analysis.md.

    python -m benchmarks.calibrate_genes [--studies 100] [--seed 0]

* per-gene FWER (max-T) and FDR (BH, share of studies with any false discovery — under the
  complete null FDR = FWER) on null data: groups without a shift; emotions that share a
  prototype (one emotion's repetitions 0 and 1 labelled as two emotions);
* power: a planted group shift of +0.3 and +0.6 on browInnerUp (happy) found on that gene;
  and whether max-T's other rejections under the shift are false: each gene × emotion's true
  group difference is estimated from one study of ``--truth-participants`` per group; a cell is
  "moved" when that difference's Welch p is below 0.001 (a real knock-on of the shift: the
  simulated participants evolve the other genes toward a target that now raises browInnerUp),
  and max-T's strong FWER is the share of studies rejecting any cell that is not moved;
* condition tests: identity and interaction at α on null; identity power on a planted shift;
* position-bias test: per-participant rejection rate under uniform picks.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from dataclasses import replace

import numpy as np

import emogen
from benchmarks.exact import share
from emogen.analysis.conditions import condition_tests
from emogen.analysis.genes import GeneTestOptions, emotion_gene_tests, group_gene_tests
from emogen.analysis.quality import position_bias
from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people
from emogen.tasks.simulated import SimulatedDesign

ALPHA = 0.05
OPTS = GeneTestOptions(permutations=2000)
NULL = PeopleDesign(
    emotions=("happy", "sad"),
    identities=("female-medium",),
    participants=40,
    repetitions=2,
    categorise=False,
    groups=("a", "b"),
    participant=SimulatedDesign(spread=0.1),
)


def rate(hits: int, n: int) -> str:
    p = hits / n
    return f"{p:.3f} ± {math.sqrt(p * (1 - p) / n):.3f} (SE; {share(hits, n)})"


def same_prototype(people):  # type: ignore[no-untyped-def]
    f = people.faces[people.faces["emotion"] == "happy"].copy()
    f["emotion"] = np.where(f["repetition"] == 0, "A", "B")
    return replace(people, faces=f)


def planted(amount: float, participants: int = NULL.participants) -> PeopleDesign:
    return replace(
        NULL, participants=participants, shifts={"b": {"happy": {"browInnerUp": amount}}}
    )


def moved_cells(rig, amount: float, per_group: int, seed: int) -> set[tuple[str, str]]:  # type: ignore[no-untyped-def]
    """The (emotion, gene) cells whose group difference is detectable (Welch p < 0.001) in
    one study of ``per_group`` participants per group with the shift planted."""
    from scipy import stats

    from emogen.analysis.genes import participant_gene_means

    people = as_people(simulate_people(planted(amount, 2 * per_group), rig, seed=seed))
    means = participant_gene_means(people)
    group = people.faces.groupby("participant_id")["group"].first()
    moved = set()
    for emotion, rows in means.groupby("emotion"):
        g = group.reindex(rows["participant_id"]).to_numpy()
        for gene in people.genes:
            a, b = rows[gene].to_numpy()[g == "a"], rows[gene].to_numpy()[g == "b"]
            if stats.ttest_ind(b, a, equal_var=False).pvalue < 1e-3:
                moved.add((str(emotion), gene.removeprefix("g_")))
    return moved


def genes(rig, studies: int, seed: int = 0, truth: int = 1000) -> None:  # type: ignore[no-untyped-def]
    g_fwer = g_fdr = e_fwer = e_fdr = 0
    power = {0.3: 0, 0.6: 0}
    wrong = {0.3: 0, 0.6: 0}
    false = {0.3: 0, 0.6: 0}
    moved = {a: moved_cells(rig, a, truth, seed=900_000 + seed) for a in power}
    for a, cells in moved.items():
        if ("happy", "browInnerUp") not in cells:
            raise SystemExit(
                f"the truth study ({truth} participants per group) did not find the planted "
                f"+{a} shift on browInnerUp itself, so it cannot tell which cells moved: use "
                "more --truth-participants (the docs' figures use 1000)"
            )
    for a in power:
        print(f"  +{a}: cells moved at {truth} per group: {sorted(moved[a])}")
    for s in range(seed, seed + studies):
        people = as_people(simulate_people(NULL, rig, seed=1000 + s))
        rng = np.random.default_rng(s)
        g = group_gene_tests(people, OPTS, rng=rng)
        e = emotion_gene_tests(same_prototype(people), OPTS, rng=rng)
        g_fwer += bool(g["significant_maxt"].any())
        g_fdr += bool(g["significant_bh"].any())
        e_fwer += bool(e["significant_maxt"].any())
        e_fdr += bool(e["significant_bh"].any())
        for amount in power:
            pp = as_people(simulate_people(planted(amount), rig, seed=5000 + s))
            t = group_gene_tests(pp, OPTS, rng=rng)
            hit = t[t["significant_maxt"]]
            power[amount] += bool(
                ((hit["gene"] == "browInnerUp") & (hit["emotion"] == "happy")).any()
            )
            wrong[amount] += bool(
                ((hit["gene"] != "browInnerUp") | (hit["emotion"] != "happy")).any()
            )
            cells = zip(hit["emotion"].astype(str), hit["gene"].astype(str), strict=True)
            false[amount] += any(c not in moved[amount] for c in cells)
    print(
        f"genes: {NULL.participants} participants (20/group), 2 emotions, 2 repetitions, "
        f"{len(g) // 2} genes"
    )
    print(
        f"  groups, no shift:   FWER (max-T) {rate(g_fwer, studies)}; any BH discovery {rate(g_fdr, studies)}"
    )
    print(
        f"  emotions, same prototype: FWER (max-T) {rate(e_fwer, studies)}; any BH discovery {rate(e_fdr, studies)}"
    )
    for amount in power:
        print(
            f"  planted +{amount} browInnerUp (happy, group b): found (max-T) {rate(power[amount], studies)}; "
            f"another gene/emotion rejected {rate(wrong[amount], studies)}; "
            f"a cell not moved rejected (strong FWER) {rate(false[amount], studies)}"
        )


def conditions(rig, studies: int, seed: int = 0) -> None:  # type: ignore[no-untyped-def]
    base = PeopleDesign(
        emotions=("happy", "sad"),
        participants=20,
        repetitions=1,
        categorise=False,
        participant=SimulatedDesign(spread=0.1),
    )
    shift = {"mouthSmile": 0.3, "browInnerUp": 0.3, "eyeWide": 0.3}
    planted = replace(base, identity_shifts={"male-medium": {"happy": shift, "sad": shift}})
    null = {"identity": 0, "emotion × identity": 0}
    found = 0
    for s in range(seed, seed + studies):
        rng = np.random.default_rng(s)
        t = condition_tests(
            as_people(simulate_people(base, rig, seed=2000 + s)),
            permutations=1000,
            bootstrap=50,
            level=0.95,
            rng=rng,
        ).set_index("effect")
        for k in null:
            null[k] += bool(t.loc[k, "p_perm"] < ALPHA)
        t = condition_tests(
            as_people(simulate_people(planted, rig, seed=7000 + s)),
            permutations=1000,
            bootstrap=50,
            level=0.95,
            rng=rng,
        ).set_index("effect")
        found += bool(t.loc["identity", "p_perm"] < ALPHA)
    print(f"conditions: {base.participants} participants, 2 emotions × 2 identities")
    for k, v in null.items():
        print(f"  {k}, null: rejection rate {rate(v, studies)}")
    print(f"  identity, planted +0.3 on 3 genes: power {rate(found, studies)}")


def positions(studies: int, seed: int = 0) -> None:
    rng = np.random.default_rng(9 + seed)
    rejected = total = 0
    import pandas as pd

    for _ in range(max(1, studies // 10)):
        rows = [
            (f"p{p}", p, t, 0, 0, int(pos))
            for p in range(50)
            for t in range(24)
            for pos in rng.choice(10, size=3, replace=False)
        ]
        picks = pd.DataFrame(
            rows,
            columns=["participant_id", "session_id", "trial", "attempt", "generation", "position"],
        )
        table, _ = position_bias(picks, 10, draws=1000, rng=rng)
        rejected += int((table["p_mc"] < ALPHA).sum())
        total += len(table)
    print(
        f"position bias, uniform picks (24 generations × 3 picks): per-participant rejection {rate(rejected, total)}"
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--studies", type=int, default=100)
    ap.add_argument(
        "--seed",
        type=int,
        default=0,
        help="first study seed (0: the seeds of the docs' figures; another: a fresh-seed confirmation)",
    )
    ap.add_argument(
        "--truth-participants",
        type=int,
        default=1000,
        help="participants per group of the study that decides which cells the shift moved",
    )
    ap.add_argument(
        "--parts",
        nargs="+",
        choices=("genes", "conditions", "positions"),
        default=["genes", "conditions", "positions"],
    )
    a = ap.parse_args()
    if a.studies < 1 or a.truth_participants < 2:
        ap.error(
            f"--studies must be at least 1 and --truth-participants at least 2; got "
            f"{a.studies} and {a.truth_participants}"
        )
    rig = emogen.load_model(os.environ["EMOGEN_MODEL"]).rig
    start = time.perf_counter()
    if "genes" in a.parts:
        genes(rig, a.studies, a.seed, a.truth_participants)
    if "conditions" in a.parts:
        conditions(rig, a.studies, a.seed)
    if "positions" in a.parts:
        positions(a.studies, a.seed)
    print(f"({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
