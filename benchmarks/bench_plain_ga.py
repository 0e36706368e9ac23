"""EmoGen's 500-run CD simulation against a plain vectorised numpy Algorithm 1 (issue #30 item 6).

The plain version below is written for comparison only: the same algorithm (protocol
initialisation from the rig's emotion blocks, Algorithm 1's slots: elite, mean of all
selections, mean of elite and one other, crossover + mutation, random faces; the observer picks
the faces closest by cosine distance), vectorised over runs, with *one* generator for all runs
and no per-run seeding, recording or replay guarantees. EmoGen's runs each draw from their own
per-run, per-generation generators (so any run replays from its seed); that is the cost compared.
Target: EmoGen's compute ≤ 1.2 × the plain version's. Both are timed best of ``REPEAT``; the
plain version's mean final error is printed beside EmoGen's as a check it is the same algorithm.

Run: ``python benchmarks/bench_plain_ga.py`` (EMOGEN_MODEL names the model; the rig is enough).
"""

from __future__ import annotations

import os
import time

import numpy as np

from emogen.config import SimulationConfig
from emogen.model.rig import Rig

RUNS, REPEAT, TARGET_RATIO = 500, 7, 1.2
TARGET = {"jawOpen": 1.0, "noseSneer": 0.6}


def _cd(shown: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Cosine distance of faces (..., S) to the target (S,)."""
    norm = np.linalg.norm(shown, axis=-1) * np.linalg.norm(target)
    dot = shown @ target
    return 1.0 - np.divide(dot, norm, out=np.zeros_like(dot), where=norm > 0)


def _init(rng, blocks, n_genes, runs, lo, hi, per_emotion, arbitrary):
    """Protocol initialisation for all runs: emotion faces from their blocks (core first),
    arbitrary faces, one neutral face, shuffled."""
    faces = []
    for core, optional in blocks:
        pool = np.concatenate([core, optional])
        for _ in range(per_emotion):
            keys = (
                rng.random((runs, len(pool))) + np.r_[np.zeros(len(core)), np.ones(len(optional))]
            )
            order = pool[np.argsort(keys, axis=1)]
            n = rng.integers(lo, hi + 1, size=runs)
            face = np.zeros((runs, n_genes))
            keep = np.arange(len(pool)) < n[:, None]
            rows = np.broadcast_to(np.arange(runs)[:, None], order.shape)
            face[rows[keep], order[keep]] = rng.random(int(keep.sum()))
            faces.append(face)
    for _ in range(arbitrary):
        order = np.argsort(rng.random((runs, n_genes)), axis=1)
        n = rng.integers(lo, hi + 1, size=runs)
        keep = np.arange(n_genes) < n[:, None]
        face = np.zeros((runs, n_genes))
        rows = np.broadcast_to(np.arange(runs)[:, None], order.shape)
        face[rows[keep], order[keep]] = rng.random(int(keep.sum()))
        faces.append(face)
    faces.append(np.zeros((runs, n_genes)))
    genes = np.stack(faces, axis=1)
    perm = np.argsort(rng.random((runs, genes.shape[1])), axis=1)
    return genes[np.arange(runs)[:, None], perm]


def _mutate(rng, faces: np.ndarray, m: int) -> None:
    runs, k = faces.shape
    idx = rng.integers(0, k, size=(runs, m))
    faces[np.arange(runs)[:, None], idx] = rng.random((runs, m))


def plain_algorithm1(rig, target_w, runs: int, cfg, rng: np.random.Generator) -> np.ndarray:
    """Final elite CD error of ``runs`` runs of Algorithm 1, plain numpy, one generator."""
    ga = cfg.ga
    expansion = rig.expansion_matrix(ga.eye_motion)
    names = rig.gene_names(ga.eye_motion)
    index = {g: i for i, g in enumerate(names)}
    blocks = [
        (
            np.array([index[g] for g in rig.emotions[e].core if g in index], dtype=np.int64),
            np.array([index[g] for g in rig.emotions[e].optional if g in index], dtype=np.int64),
        )
        for e in ga.init.emotions
    ]
    lo, hi = ga.init.activation_range
    genes = _init(
        rng, blocks, len(names), runs, lo, hi, ga.init.faces_per_emotion, ga.arbitrary_faces()
    )
    n, k = genes.shape[1:]
    r = np.arange(runs)
    for g in range(ga.generations + 1):
        error = _cd(genes @ expansion, target_w)
        order = np.argsort(error, axis=1, kind="stable")
        if g == ga.generations:
            return error[r, order[:, 0]]
        s = min(cfg.selections_at(g), n)
        sel = order[:, :s]
        elite = genes[r, sel[:, 0]]
        new = np.zeros_like(genes)
        new[:, 0] = elite
        for slot in range(2, n - ga.random_faces + 1):
            i = slot - 1
            if slot == 2 and s > 2:
                new[:, i] = genes[r[:, None], sel].mean(axis=1)
            elif slot == 3 and g not in (1, 2):
                if s >= 2:
                    other = sel[r, 1 + rng.integers(0, s - 1, size=runs)]
                    new[:, i] = (elite + genes[r, other]) / 2
                else:
                    new[:, i] = genes[:, i]
            else:
                if s >= 2:
                    a = rng.integers(0, s, size=runs)
                    b = rng.integers(0, s - 1, size=runs)
                    b += b >= a
                    pa, pb = genes[r, sel[r, a]], genes[r, sel[r, b]]
                    child = np.where(rng.random((runs, k)) < 0.5, pb, pa)
                else:
                    child = elite.copy()
                _mutate(rng, child, ga.mutation_genes)
                new[:, i] = child
        for i in range(n - ga.random_faces, n):
            face = np.zeros((runs, k))
            _mutate(rng, face, ga.random_genes)
            new[:, i] = face
        genes = new
    raise AssertionError("unreachable")


def run(rig: Rig) -> dict[str, float]:
    from emogen.simulate.runner import run_simulation

    cfg = SimulationConfig.model_validate(
        {"target": TARGET, "runs": RUNS, "seed": 1, "metric": "cd"}
    )
    target_w = rig.weights_from_names(TARGET)
    emogen_s, plain_s = [], []
    final = plain = np.empty(0)
    for rep in range(REPEAT):  # interleaved, so load from elsewhere hits both alike
        result = run_simulation(cfg, rig)
        emogen_s.append(float(result.record["compute_seconds"]))
        t = time.perf_counter()
        plain = plain_algorithm1(rig, target_w, RUNS, cfg, np.random.default_rng(rep))
        plain_s.append(time.perf_counter() - t)
        table = result.table
        final = table.loc[table["generation"] == table["generation"].max(), "elite_error"]
    ratio = min(emogen_s) / min(plain_s)
    print(f"\n== {RUNS}-run CD simulation, compute seconds (best of {REPEAT}) ==")
    print(f"EmoGen (per-run seeded, replayable)  {min(emogen_s):.3f}")
    print(f"plain vectorised numpy Algorithm 1   {min(plain_s):.3f}")
    print(f"ratio {ratio:.2f} (target ≤ {TARGET_RATIO})")
    print(
        f"final elite CD error: EmoGen {final.mean():.4f} ± {final.std() / np.sqrt(RUNS):.4f}, "
        f"plain {plain.mean():.4f} ± {plain.std() / np.sqrt(RUNS):.4f} (mean ± SE)"
    )
    return {"emogen_s": min(emogen_s), "plain_s": min(plain_s), "ratio": ratio}


if __name__ == "__main__":
    from emogen.model import load_model

    path = os.environ.get("EMOGEN_MODEL", "/work/shared/ict-facekit/FaceXModel")
    run(load_model(path).rig)
