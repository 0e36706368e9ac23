"""Dynamic faces: interpenetration between correction keyframes, and the cost of correcting them.

Faces come from dynamic GA runs (protocol initialisation, then generations bred from random
selections). Every face is shown over its clip at ``--fps`` dense frames (default 100/s); for
each keyframe count the correctives are computed at the keyframes only and interpolated
(:func:`emogen.ga.motion.frames`, what the page shows), and every dense frame is tested by the
independent winding-number test (:class:`emogen.correct.measure.Interpenetration`). Printed per
keyframe count: the share of (face, frame) pairs that interpenetrate deeper than the contact
tolerance, uncorrected and with the interpolated correctives, the deepest vertex (mm), and the
correction time of one population's keyframes.

``python benchmarks/bench_motion.py [--faces N] [--fps F] [--keyframes 6,11,21,76]``
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from emogen.config import GAConfig
from emogen.correct import correct_faces, corrected_vertices
from emogen.correct.lips import mouth_geometry
from emogen.correct.measure import Interpenetration
from emogen.ga.engine import Engine
from emogen.ga.genome import DynamicGenome
from emogen.ga.motion import correct_keyframes, frames


def dynamic_faces(model, n: int, seed: int = 0) -> np.ndarray:  # type: ignore[no-untyped-def]
    """(n, K, 6) genes of faces shown in dynamic GA runs with random selections."""
    rng = np.random.default_rng(seed)
    out: list[np.ndarray] = []
    run = 0
    while sum(len(g) for g in out) < n:
        engine = Engine(
            GAConfig(generations=4), model.rig, seed * 1000 + run, genome=DynamicGenome()
        )
        run += 1
        while not engine.done:
            pop = engine.ask()
            out.append(pop.genes)
            ids = rng.permutation(pop.ids)[: int(rng.integers(1, 5))]
            engine.tell(int(ids[0]), [int(i) for i in ids[1:]])
    return np.concatenate(out)[:n]


def shown_vertices(model, full: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Vertices of faces given as full weights (shapes, then correctives): the effective shape
    weights (companions capped) as the corrector makes them, the given correctives added."""
    s = model.n_shapes
    base = correct_faces(model, full[:, :s], collisions=False)
    n_comb = len(base.combinational_names)
    result = replace(base, combinational=full[:, s : s + n_comb], collision=full[:, s + n_comb :])
    return corrected_vertices(model, result, gaze=False)


def measure(model, genes: np.ndarray, keyframes: int, fps: float, test) -> dict[str, float]:  # type: ignore[no-untyped-def]
    genome = DynamicGenome(keyframes=keyframes)
    expand = lambda g: model.rig.expand(g, True)  # noqa: E731
    correct = lambda w: (lambda r: (r.corrective_names, r.correctives))(correct_faces(model, w))  # noqa: E731
    correct_keyframes(genome, genes[10:20], expand, correct)  # warm the corrector
    start = time.process_time()
    _, keyed = correct_keyframes(genome, genes[:10], expand, correct)
    cost = time.process_time() - start
    _, keyed = correct_keyframes(genome, genes, expand, correct)
    t = np.arange(0, genome.clip_s + 1e-9, 1 / fps)
    shown = frames(genome, genes, keyed, t, expand).reshape(len(genes) * len(t), -1)
    plain = frames(genome, genes, None, t, expand).reshape(len(genes) * len(t), -1)
    moving = np.flatnonzero(plain.any(axis=1))
    before = after = 0
    deepest = 0.0
    for chunk in np.array_split(moving, max(1, len(moving) // 64)):
        v0 = model.evaluate(plain[chunk], gaze=False)
        before += int(test.penetrating(v0).sum())
        v1 = shown_vertices(model, shown[chunk])
        for v in v1:
            d = float(test.depths(v).max())
            deepest = max(deepest, d)
            after += d > 0.02
    total = len(genes) * len(t)
    return {
        "keyframes": keyframes,
        "uncorrected": before / total,
        "interpolated": after / total,
        "deepest_mm": 10 * deepest,
        "cost_s": cost,
    }


def main() -> None:
    import emogen

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--faces", type=int, default=60)
    parser.add_argument("--fps", type=float, default=100.0)
    parser.add_argument("--keyframes", default="6,11,21,76")
    args = parser.parse_args()
    model = emogen.load_model()
    genes = dynamic_faces(model, args.faces)
    mouth = mouth_geometry(model.base_neutral.astype(np.float64), model.polygons, model.regions)
    test = Interpenetration.build(model.base_neutral.astype(np.float64), model.regions, mouth)
    print(f"{args.faces} dynamic GA faces, {args.fps:g} frames/s over the clip")
    print(
        "keyframes  frames interpenetrating: uncorrected  interpolated  deepest   10 faces' keyframes"
    )
    for k in (int(v) for v in args.keyframes.split(",")):
        r = measure(model, genes, k, args.fps, test)
        print(
            f"{k:9d}  {r['uncorrected']:33.2%}  {r['interpolated']:12.3%}  "
            f"{r['deepest_mm']:5.2f} mm  {1000 * r['cost_s']:6.0f} ms CPU"
        )


if __name__ == "__main__":
    main()
