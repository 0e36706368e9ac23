"""EmoGen's 500-run CD simulation against plain vectorised numpy Algorithm 1 (issue #30 item 6).

The plain versions below are written for comparison only, straight from the paper: protocol
initialisation from the rig's emotion blocks, Algorithm 1's slots (elite, mean of all
selections, mean of elite and one other, crossover + mutation, random faces), an observer that
picks the faces closest by cosine distance; runs advanced together as arrays. Two of them:

* **plain, per-run generators** — the comparison the target is measured against. It does the
  work EmoGen's simulation must do: every run draws from its own generators, generation g of
  the run with seed s from ``default_rng(SeedSequence(s, spawn_key=(0, g)))`` (so any run, and
  any participant's session, replays from its seed alone: the engine's contract), generation 0
  with the generator's own methods run by run, later generations from one block of doubles per
  run read front to back (stream 2, :mod:`emogen.ga.draws`); it keeps every generation's errors
  and selections (what the tables are made of). The generators are built by
  :func:`emogen.rng.generation_rngs` (numpy's ``default_rng`` one by one, as EmoGen builds
  them), so the seeding is not what is compared. It returns the same numbers as EmoGen, bit for bit (checked below): the
  same algorithm, the same draws, the same selections.
* **plain, one generator** — all runs from one generator in a few calls, no per-run seeds: the
  cost of a simulation that could not replay a run from its seed. Shown for scale only; it
  cannot give EmoGen's numbers.

Target: EmoGen's compute (``compute_seconds``: the runs, not the tables) ≤ 1.2 × the plain
per-run version's. Timed interleaved, median of ``REPEAT``.

Figures (shared 2-core VM under load 4–6, three runs each, medians of 9): before #30's speed
work EmoGen 0.118–0.176 s against plain per-run 0.096–0.136 s, 1.21–1.29×; after it
0.101–0.192 s against 0.093–0.182 s, 1.05–1.16× (1.07–1.10× in three more runs); the
one-generator version 0.034–0.068 s (ours 2.8–3.1× it). Issue 38 (generators one by one with
numpy's public API on both sides, load 6–7, two runs each): EmoGen 0.30–0.46 s against
0.33–0.55 s, 0.84–0.94× (before it, the same runs: 0.20–0.27 s against 0.20–0.26 s,
1.01–1.02×). See docs/ga.md.

Run: ``python benchmarks/bench_plain_ga.py`` (EMOGEN_MODEL names the model; the rig is enough).
"""

from __future__ import annotations

import os
import time

import numpy as np

from emogen.config import SimulationConfig
from emogen.model.rig import Rig
from emogen.rng import generation_rngs, spawn_seeds

RUNS, REPEAT, TARGET_RATIO = 500, 9, 1.2
TARGET = {"jawOpen": 1.0, "noseSneer": 0.6}


def _cd(shown: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Cosine distance of faces (..., S) to the target (S,), as eq. 12 (zero face: 1)."""
    norm = np.sqrt((shown * shown).sum(-1)) * np.sqrt((target * target).sum())
    dot = (shown * target).sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cd = 1.0 - dot / norm
    return np.clip(np.where(norm == 0, 1.0, cd), 0.0, 2.0)


def _blocks(rig: Rig, cfg: SimulationConfig) -> list[tuple[np.ndarray, np.ndarray]]:
    names = rig.gene_names(cfg.ga.eye_motion)
    index = {g: i for i, g in enumerate(names)}
    return [
        (
            np.array([index[g] for g in rig.emotions[e].core if g in index], dtype=np.int64),
            np.array([index[g] for g in rig.emotions[e].optional if g in index], dtype=np.int64),
        )
        for e in cfg.ga.init.emotions
    ]


# ---- plain, per-run generators ----------------------------------------------------------------
def _init_run(rng, blocks, n_genes, lo, hi, per_emotion, arbitrary) -> np.ndarray:
    """Generation 0 of one run from its own generator: emotion faces (core blocks first, then
    optional, up to n), arbitrary faces, a neutral face, shuffled."""
    genes = np.zeros((len(blocks) * per_emotion + arbitrary + 1, n_genes))
    f = 0
    for core, optional in blocks:
        for _ in range(per_emotion):
            n = int(rng.integers(lo, hi + 1))
            order = np.concatenate((rng.permutation(core), rng.permutation(optional)))[:n]
            genes[f, order] = rng.random(len(order))
            f += 1
    for _ in range(arbitrary):
        n = int(rng.integers(lo, hi + 1))
        chosen = rng.choice(n_genes, size=min(n, n_genes), replace=False)
        genes[f, chosen] = rng.random(len(chosen))
        f += 1
    return genes[rng.permutation(len(genes))]


def _set(faces: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """faces[r, i, index[r, i, j]] = values[r, i, j] (later j wins)."""
    r, n, k = faces.shape
    rows = np.repeat(np.arange(r * n), index.shape[-1])
    faces.reshape(r * n, k)[rows, index.reshape(-1)] = values.reshape(-1)


def _breed(genes, sel, g, u, n_random, m, x) -> np.ndarray:
    """P_{g+1} from P_g, the selections (R, s) and each run's block of doubles u (R, B)."""
    runs, n, k = genes.shape
    s, r, at = sel.shape[1], np.arange(runs), 0

    def take(count: int) -> np.ndarray:
        nonlocal at
        at += count
        return u[:, at - count : at]

    def index(high: int, count: int) -> np.ndarray:
        return np.minimum(np.floor(take(count) * high).astype(np.int64), high - 1)

    new = np.zeros_like(genes)
    elite = genes[r, sel[:, 0]]
    new[:, 0] = elite
    for i in range(1, n - n_random):
        if i == 1 and s > 2:
            new[:, i] = genes[r[:, None], sel].mean(axis=1)
        elif i == 2 and g not in (1, 2):
            if s >= 2:
                other = sel[r, 1 + index(s - 1, 1)[:, 0]]
                new[:, i] = np.stack([elite, genes[r, other]], axis=1).mean(axis=1)
            else:
                new[:, i] = genes[:, i]
        else:
            if s >= 2:
                a, b = index(s, 1)[:, 0], index(s - 1, 1)[:, 0]
                b += b >= a
                pa, pb = genes[r, sel[r, a]], genes[r, sel[r, b]]
                child = np.where(take(k) < 0.5, pb, pa)
            else:
                child = elite.copy()
            _set(child[:, None], index(k, m)[:, None], take(m)[:, None])
            new[:, i] = child
    idx, values = index(k, n_random * x), take(n_random * x)
    faces = np.zeros((runs, n_random, k))
    _set(faces, idx.reshape(runs, n_random, x), values.reshape(runs, n_random, x))
    new[:, n - n_random :] = faces
    return new


def plain_per_run(rig: Rig, target_w: np.ndarray, seeds: np.ndarray, cfg: SimulationConfig):
    """(CD errors (R, G+1, N), selections (R, G+1, N), −1 padded) of runs with these seeds."""
    ga = cfg.ga
    expansion = rig.expansion_matrix(ga.eye_motion)
    blocks, k = _blocks(rig, cfg), len(rig.gene_names(ga.eye_motion))
    lo, hi = ga.init.activation_range
    args = (blocks, k, lo, hi, ga.init.faces_per_emotion, ga.arbitrary_faces())
    genes = np.stack([_init_run(rng, *args) for rng in generation_rngs(seeds, 0, 0)])
    runs, n = genes.shape[:2]
    errors = np.empty((runs, ga.generations + 1, n))
    chosen = np.full((runs, ga.generations + 1, n), -1, dtype=np.int64)
    width = n * (3 + k + 2 * ga.mutation_genes + 2 * ga.random_genes)
    for g in range(ga.generations + 1):
        errors[:, g] = _cd(genes @ expansion, target_w)
        order = np.argsort(errors[:, g], axis=1, kind="stable")
        s = 1 if g == ga.generations else min(cfg.selections_at(g), n)
        chosen[:, g, :s] = order[:, :s]
        if g < ga.generations:
            u = np.empty((runs, width))
            for rng, row in zip(generation_rngs(seeds, 0, g + 1), u, strict=True):
                rng.random(out=row)
            params = (ga.random_faces, ga.mutation_genes, ga.random_genes)
            genes = _breed(genes, order[:, :s], g, u, *params)
    return errors, chosen


# ---- plain, one generator -----------------------------------------------------------------------
def _faces(rng, runs: int, k: int, pool: np.ndarray, lo: int, hi: int, first: int = 0):
    """One face per run: n ~ U{lo..hi} genes of ``pool`` (its ``first`` ones first), U(0,1)."""
    keys = rng.random((runs, len(pool))) + (np.arange(len(pool)) >= first)
    order = pool[np.argsort(keys, axis=1)]
    keep = np.arange(len(pool)) < rng.integers(lo, hi + 1, size=runs)[:, None]
    face = np.zeros((runs, k))
    rows = np.broadcast_to(np.arange(runs)[:, None], order.shape)
    face[rows[keep], order[keep]] = rng.random(int(keep.sum()))
    return face


def plain_one_generator(rig: Rig, target_w, runs: int, cfg, rng: np.random.Generator):
    """Final elite CD error of ``runs`` runs, every draw from one generator ``rng``."""
    ga = cfg.ga
    expansion = rig.expansion_matrix(ga.eye_motion)
    k = len(rig.gene_names(ga.eye_motion))
    lo, hi = ga.init.activation_range
    faces = [
        _faces(rng, runs, k, np.concatenate([core, opt]), lo, hi, first=len(core))
        for core, opt in _blocks(rig, cfg)
        for _ in range(ga.init.faces_per_emotion)
    ]
    faces += [_faces(rng, runs, k, np.arange(k), lo, hi) for _ in range(ga.arbitrary_faces())]
    genes = np.stack([*faces, np.zeros((runs, k))], axis=1)
    genes = genes[np.arange(runs)[:, None], np.argsort(rng.random(genes.shape[:2]), axis=1)]
    n = genes.shape[1]
    width = n * (3 + k + 2 * ga.mutation_genes + 2 * ga.random_genes)
    for g in range(ga.generations + 1):
        error = _cd(genes @ expansion, target_w)
        order = np.argsort(error, axis=1, kind="stable")
        if g == ga.generations:
            return error[np.arange(runs), order[:, 0]]
        s = min(cfg.selections_at(g), n)
        u = rng.random((runs, width))
        genes = _breed(
            genes, order[:, :s], g, u, ga.random_faces, ga.mutation_genes, ga.random_genes
        )
    raise AssertionError("unreachable")


def run(rig: Rig) -> dict[str, float]:
    from emogen.simulate.runner import run_simulation

    cfg = SimulationConfig.model_validate(
        {"target": TARGET, "runs": RUNS, "seed": 1, "metric": "cd"}
    )
    target_w = rig.weights_from_names(TARGET)
    seeds = np.array(spawn_seeds(1, RUNS), dtype=np.int64)
    times: dict[str, list[float]] = {"emogen": [], "per_run": [], "one": []}
    for rep in range(REPEAT):  # interleaved, so load from elsewhere hits all alike
        result = run_simulation(cfg, rig)
        times["emogen"].append(float(result.record["compute_seconds"]))
        t = time.perf_counter()
        errors, chosen = plain_per_run(rig, target_w, seeds, cfg)
        times["per_run"].append(time.perf_counter() - t)
        t = time.perf_counter()
        one = plain_one_generator(rig, target_w, RUNS, cfg, np.random.default_rng(rep))
        times["one"].append(time.perf_counter() - t)
    table = result.table
    ours = table["elite_error"].to_numpy().reshape(RUNS, -1)
    plain = np.take_along_axis(errors, chosen[:, :, :1], axis=2)[:, :, 0]
    same = np.array_equal(ours, plain)
    med = {name: float(np.median(v)) for name, v in times.items()}
    ratio = med["emogen"] / med["per_run"]
    print(f"\n== {RUNS}-run CD simulation, compute seconds (median of {REPEAT}, interleaved) ==")
    print(f"EmoGen (run_simulation)                     {med['emogen']:.3f}")
    print(f"plain numpy, per-run generators (the same)  {med['per_run']:.3f}")
    print(f"plain numpy, one generator (no replay)      {med['one']:.3f}")
    print(
        f"ratio EmoGen / plain per-run {ratio:.2f} (target ≤ {TARGET_RATIO}); "
        f"/ one generator {med['emogen'] / med['one']:.2f}"
    )
    print(f"plain per-run gives EmoGen's elite errors bit for bit: {same}")
    final = ours[:, -1]
    print(
        f"final elite CD error: EmoGen {final.mean():.4f} ± {final.std() / np.sqrt(RUNS):.4f}, "
        f"one generator {one.mean():.4f} ± {one.std() / np.sqrt(RUNS):.4f} (mean ± SE)"
    )
    if not same:
        raise AssertionError("the plain per-run version must give EmoGen's numbers")
    return {
        "emogen_s": med["emogen"],
        "plain_per_run_s": med["per_run"],
        "plain_one_generator_s": med["one"],
        "ratio": ratio,
        "ratio_one_generator": med["emogen"] / med["one"],
    }


if __name__ == "__main__":
    from emogen.model import load_model

    path = os.environ.get("EMOGEN_MODEL", "/work/shared/ict-facekit/FaceXModel")
    run(load_model(path).rig)
