"""Correctives: interpenetration and plausibility before/after, correction time, contact sheets.

``run(model)`` draws ≥ 10,000 faces from the GA's own generators — protocol initialisation,
random faces R(6) and evolved faces from simulated runs — corrects them, and prints

* the share of faces with interpenetration before and after correction, by the independent
  winding-number test (:class:`emogen.correct.measure.Interpenetration`), and by the detector;
* the plausibility measure (lid crossing, lip overlap, extreme stretch) without and with the
  combinational correctives;
* the correction time per face (detection + solve) on one core: median and p95;
* before/after contact sheets of the worst faces (meshes: ``.npz`` and ``.obj``; PNG sheets when
  ``emogen.render`` is available).

``python benchmarks/bench_correct.py [--faces N] [--out DIR]`` runs it alone.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from emogen.correct import correct_faces, corrected_vertices, evaluate_corrected

REPO = Path(__file__).resolve().parents[1]


# ---- faces from the GA's own generators -------------------------------------------------------
def _choose(weights: np.ndarray, target: np.ndarray, count: int) -> tuple[int, list[int]]:
    """A simulated participant: rank by cosine distance to the target; elite + the next ones."""
    norm = np.linalg.norm(weights, axis=1) * np.linalg.norm(target)
    cd = 1.0 - np.divide(weights @ target, norm, out=np.zeros(len(weights)), where=norm > 0)
    order = np.argsort(cd, kind="stable")
    return int(order[0]), [int(i) for i in order[1:count]]


def ga_faces(rig, n: int, *, seed: int = 20261121) -> tuple[np.ndarray, np.ndarray]:  # type: ignore[no-untyped-def]
    """≥ n faces, a third from each generator: (weights (N, S), source (N,) str).

    * ``protocol``: protocol initialisation (emotion faces from building blocks, arbitrary
      faces, the neutral), default settings, many draws;
    * ``random``: R(6), the GA's random faces (6 gene draws, values U(0, 1));
    * ``evolved``: every face shown in generations 1–10 of simulated runs (default GA
      settings), each run steered by a cosine-distance participant towards a target drawn
      from protocol initialisation.
    """
    from emogen.config import PAPER_SELECTIONS, GAConfig
    from emogen.ga import Engine, protocol_init, random_faces
    from emogen.ga.draws import BlockDraws

    rng = np.random.default_rng(seed)
    per = -(-n // 3)
    genes_n = len(rig.gene_names())
    rows, source = [], []
    count = 0
    while count < per:
        g, _ = protocol_init(rig, rng=rng)
        rows.append(rig.expand(g))
        count += len(g)
    source += ["protocol"] * count
    rows.append(rig.expand(random_faces(per, genes_n, 6, BlockDraws([rng], per * 12))[0]))
    source += ["random"] * per
    config = GAConfig()
    evolved = 0
    while evolved < per:
        g, labels = protocol_init(rig, rng=rng)
        target = rig.expand(g[labels != "init_neutral"][:1])[0]
        engine = Engine(config, rig, int(rng.integers(2**62)))
        while not engine.done:
            pop = engine.ask()
            if pop.generation > 0:
                rows.append(np.asarray(pop.weights))
                evolved += len(pop)
            k = PAPER_SELECTIONS[min(pop.generation, len(PAPER_SELECTIONS) - 1)]
            elite, others = _choose(np.asarray(pop.weights), target, k)
            engine.tell(int(pop.ids[elite]), [int(pop.ids[o]) for o in others])
    source += ["evolved"] * evolved
    return np.concatenate(rows), np.array(source)


# ---- measurements -----------------------------------------------------------------------------
def _interpenetration(model, weights: np.ndarray, corrected: bool) -> np.ndarray:  # type: ignore[no-untyped-def]
    from emogen.correct.lips import mouth_geometry
    from emogen.correct.measure import Interpenetration

    mouth = mouth_geometry(model.base_neutral.astype(np.float64), model.polygons, model.regions)
    test = Interpenetration.build(model.base_neutral.astype(np.float64), model.regions, mouth)
    out = np.zeros(len(weights), dtype=bool)
    for start in range(0, len(weights), 256):
        rows = weights[start : start + 256]
        verts = (
            evaluate_corrected(model, rows, gaze=False)
            if corrected
            else model.evaluate(rows, gaze=False)
        )
        out[start : start + 256] = test.penetrating(verts)
    return out


def _plausibility(model, weights: np.ndarray, combinational: bool) -> dict[str, np.ndarray]:  # type: ignore[no-untyped-def]
    from emogen.correct.lips import mouth_geometry
    from emogen.correct.measure import Plausibility

    mouth = mouth_geometry(model.base_neutral.astype(np.float64), model.polygons, model.regions)
    active = [i for i, n in enumerate(model.shape_names) if n not in model.rig.excluded]
    measure = Plausibility.build(
        model.base_neutral, model.polygons, model.regions, mouth, model.deltas[active]
    )
    parts: dict[str, list[np.ndarray]] = {}
    for start in range(0, len(weights), 256):
        w = weights[start : start + 256]
        if combinational:
            verts = corrected_vertices(model, correct_faces(model, w, collisions=False), gaze=False)
        else:
            verts = model.evaluate(w, gaze=False)
        for k, v in measure.measure(verts).items():
            parts.setdefault(k, []).append(v)
    return {k: np.concatenate(v) for k, v in parts.items()}


_TIMING_SNIPPET = """
import json, sys, time
import numpy as np
from emogen.correct import correct_faces
from emogen.model import load_model
model = load_model(sys.argv[1])
w = np.load(sys.argv[2])
correct_faces(model, w[:4])  # warm up: correctives loaded, caches filled
times, cpu, collided = [], [], []
for i in range(len(w)):
    t, c = time.perf_counter(), time.process_time()
    r = correct_faces(model, w[i : i + 1])
    times.append(time.perf_counter() - t)
    cpu.append(time.process_time() - c)
    collided.append(bool(r.collided[0]))
t = time.perf_counter()
correct_faces(model, w)
batch = time.perf_counter() - t
print(json.dumps({"times": times, "cpu": cpu, "collided": collided, "batch_s": batch}))
"""


def time_correction(model_path: str, weights: np.ndarray, tmp: Path) -> dict[str, object]:
    """Per-face correction time on one core (fresh process, BLAS limited to one thread)."""
    path = tmp / "timing_weights.npy"
    np.save(path, weights)
    env = {
        **os.environ,
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
    }
    out = subprocess.run(
        [sys.executable, "-c", _TIMING_SNIPPET, model_path, str(path)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    r = json.loads(out.stdout)
    col = np.array(r["collided"])
    figures: dict[str, object] = {"faces": len(col), "collided": float(col.mean())}
    for key, label in (("times", "wall"), ("cpu", "cpu")):
        t = np.array(r[key]) * 1000
        figures[label] = {
            "median_ms": float(np.median(t)),
            "p95_ms": float(np.percentile(t, 95)),
            "median_ms_no_collision": float(np.median(t[~col])) if (~col).any() else None,
            "median_ms_collision": float(np.median(t[col])) if col.any() else None,
        }
    figures["batch_ms_per_face"] = float(r["batch_s"] * 1000 / len(col))
    return figures


# ---- contact sheets ---------------------------------------------------------------------------
def contact_sheets(
    model, weights: np.ndarray, picks: dict[str, np.ndarray], out: Path
) -> list[Path]:  # type: ignore[no-untyped-def]
    """Before/after meshes of the picked faces; PNG sheets when a renderer is available.

    A sheet named ``combinational*`` shows the combinational correctives alone (like the
    paper's Fig. 1); the others the whole correction (Fig. 2).
    """
    from emogen.model.io.obj import write_obj

    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, idx in picks.items():
        w = weights[idx]
        before = model.evaluate(w)
        res = correct_faces(model, w, collisions=not name.startswith("combinational"))
        after = corrected_vertices(model, res)
        path = out / f"{name}.npz"
        np.savez_compressed(
            path,
            before=before,
            after=after,
            weights=w,
            correctives=res.correctives,
            corrective_names=np.array(res.corrective_names),
            faces=model.faces,
        )
        written.append(path)
        for i in range(len(idx)):
            for label, verts in (("before", before[i]), ("after", after[i])):
                p = out / f"{name}_{i:02d}_{label}.obj"
                write_obj(p, verts, model.polygons, f"EmoGen {name} face {i} ({label} correction)")
                written.append(p)
        sheet = _render_sheet(model, before, after, out / f"{name}.png")
        if sheet is not None:
            written.append(sheet)
    return written


def _render_sheet(model, before: np.ndarray, after: np.ndarray, path: Path) -> Path | None:  # type: ignore[no-untyped-def]
    """Like the paper's Figs. 1–2: row 1 before, row 2 after correction; then the same as
    mouth close-ups (the lower half of the sheet). None when no renderer works here."""
    try:
        from dataclasses import replace

        from emogen.render import Renderer, contact_sheet, default_look, save_png

        look = default_look()
        mouth = look.with_options(
            camera=replace(
                look.camera, position=(0.0, -3.6, 40.0), target=(0.0, -3.6, 10.0), fov_y_deg=12.0
            )
        )
        n = len(before)
        both = np.concatenate([before, after])
        labels = [f"{i + 1} before" for i in range(n)] + [f"{i + 1} after" for i in range(n)]
        with Renderer(model, size=320) as r:
            faces = r.render_vertices(both)
        with Renderer(model, size=320, look=mouth) as r:
            mouths = r.render_vertices(both)
        sheet = contact_sheet(np.concatenate([faces, mouths]), labels * 2, columns=n)
        save_png(path, sheet)
        return path
    except Exception as exc:  # the renderer is optional (needs EGL/OpenGL)
        print(f"  (no PNG sheet: {type(exc).__name__}: {exc}; meshes saved instead)")
        return None


# ---- the benchmark ----------------------------------------------------------------------------
def _share(x: np.ndarray) -> str:
    return f"{100 * x.mean():6.2f}% ({int(x.sum())}/{len(x)})"


def run(
    model, n_faces: int = 10_000, out: Path | None = None, model_path: str | None = None
) -> dict[str, object]:  # type: ignore[no-untyped-def]
    import tempfile

    print("\n== correctives (paper Section III-A) ==")
    t0 = time.perf_counter()
    weights, source = ga_faces(model.rig, n_faces)
    print(
        f"faces: {len(weights)} from the GA's generators "
        f"({', '.join(f'{s} {int((source == s).sum())}' for s in ('protocol', 'random', 'evolved'))})"
        f"  [{time.perf_counter() - t0:.1f} s]"
    )

    t0 = time.perf_counter()
    result = correct_faces(model, weights)
    print(f"corrected in {time.perf_counter() - t0:.1f} s (batched)")
    changed = result.collision.any(axis=1)
    pen_before = _interpenetration(model, weights, corrected=False)
    pen_after = pen_before.copy()  # a face without collision weights is unchanged there
    idx = np.flatnonzero(changed | pen_before)
    pen_after[idx] = _interpenetration(model, weights[idx], corrected=True)
    print("interpenetration (independent winding-number test: upper teeth / upper lip vertices")
    print("inside the closed lower lip deeper than 0.02 cm):")
    print(f"  before correction  {_share(pen_before)}")
    print(f"  after correction   {_share(pen_after)}")
    for s in ("protocol", "random", "evolved"):
        m = source == s
        print(f"    {s:<9} before {_share(pen_before[m])}  after {_share(pen_after[m])}")
    print(
        f"detector: collisions {_share(result.collided)}; remaining after correction {_share(result.remaining)}"
    )

    plaus_before = _plausibility(model, weights, combinational=False)
    plaus_after = _plausibility(model, weights, combinational=True)
    from emogen.correct.measure import Plausibility

    bad_b, bad_a = Plausibility.implausible(plaus_before), Plausibility.implausible(plaus_after)
    print("plausibility (without → with combinational correctives):")
    print(f"  implausible faces  {_share(bad_b)} → {_share(bad_a)}")
    for key, label in (
        ("lid_crossing", "lid crossing > 0.02 cm"),
        ("lip_overlap", "lip overlap > 0.02 cm"),
    ):
        print(
            f"  {label:<22} {_share(plaus_before[key] > 0.02)} → {_share(plaus_after[key] > 0.02)}"
            f"   mean depth {plaus_before[key].mean():.4f} → {plaus_after[key].mean():.4f} cm"
        )
    print(
        f"  {'strain beyond envelope':<22} {_share(plaus_before['stretched_edges'] > 0)} → "
        f"{_share(plaus_after['stretched_edges'] > 0)}   mean worst excess "
        f"{plaus_before['excess'].mean():.3f} → {plaus_after['excess'].mean():.3f}; edges "
        f"{plaus_before['stretched_edges'].mean():.1f} → {plaus_after['stretched_edges'].mean():.1f}"
    )

    rng = np.random.default_rng(1)
    sample = weights[rng.choice(len(weights), size=min(1000, len(weights)), replace=False)]
    with tempfile.TemporaryDirectory() as tmp:
        timing = time_correction(model_path or model.source, sample, Path(tmp))
    print(
        f"correction time per face, one core (detection + solve), {timing['faces']} faces "
        "one at a time, BLAS on one thread:"
    )
    for label in ("wall", "cpu"):
        t = timing[label]
        print(
            f"  {label:<4} median {t['median_ms']:.2f} ms   p95 {t['p95_ms']:.2f} ms   "
            f"(no collision {t['median_ms_no_collision']:.2f} ms, "
            f"collision {t['median_ms_collision']:.2f} ms)"
        )
    print(f"  batched (all at once): {timing['batch_ms_per_face']:.2f} ms/face wall")

    out = out or REPO / "out" / "correctives"
    depth_b = result.within_before.sum(1)
    worst = np.argsort(-depth_b, kind="stable")[:6]
    teeth = np.argsort(-result.within_before[:, 1], kind="stable")[:6]
    comb = np.argsort(-(plaus_before["excess"] - plaus_after["excess"]), kind="stable")[:6]
    written = contact_sheets(
        model,
        weights,
        {"collision_lips": worst, "collision_teeth": teeth, "combinational": comb},
        out,
    )
    print(f"contact sheets (before/after): {len(written)} files in {out}")
    return {
        "faces": len(weights),
        "interpenetration_before": float(pen_before.mean()),
        "interpenetration_after": float(pen_after.mean()),
        "detector_before": float(result.collided.mean()),
        "detector_after": float(result.remaining.mean()),
        "implausible_before": float(bad_b.mean()),
        "implausible_after": float(bad_a.mean()),
        "timing": timing,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--faces", type=int, default=10_000)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    from benchmarks.run import model_path
    from emogen.model import load_model

    path = model_path()
    figures = run(load_model(path), args.faces, args.out, path)
    print(json.dumps(figures, indent=2))


if __name__ == "__main__":
    sys.path.insert(0, str(REPO))
    main()
