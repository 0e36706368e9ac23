"""EmoGen benchmarks: `python benchmarks/run.py [--quick] [--json FILE]` prints every figure.

Model: $EMOGEN_MODEL, else ../shared/ict-facekit/FaceXModel beside the repository.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def model_path() -> str:
    return os.environ.get("EMOGEN_MODEL") or str(
        REPO.parent / "shared" / "ict-facekit" / "FaceXModel"
    )


_LOAD_SNIPPET = """
import time, json, sys
t0 = time.perf_counter()
from emogen.model import load_model
t1 = time.perf_counter()
m = load_model(sys.argv[1])
t2 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "load_s": t2 - t1, "vertices": m.n_vertices}))
"""


def bench_load(path: str) -> dict[str, float]:
    """Cold (empty cache: parse every OBJ) and warm (compiled cache) loads, each in a fresh process."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "EMOGEN_CACHE_DIR": cache}

        def run() -> dict[str, float]:
            out = subprocess.run(
                [sys.executable, "-c", _LOAD_SNIPPET, path],
                env=env,
                capture_output=True,
                text=True,
                check=True,
            )
            return json.loads(out.stdout)

        cold = run()
        warm = min((run() for _ in range(3)), key=lambda r: r["load_s"])
    return {
        "cold_load_s": cold["load_s"],
        "warm_load_s": warm["load_s"],
        "warm_import_s": warm["import_s"],
    }


def loop_blend(neutral: np.ndarray, deltas: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The naive reference: per face, per shape, v += w[k] * delta[k]."""
    out = np.empty((len(w), *neutral.shape), dtype=np.float32)
    for i in range(len(w)):
        v = neutral.copy()
        for k in range(len(deltas)):
            v += w[i, k] * deltas[k]
        out[i] = v
    return out


def timed(fn, repeat: int) -> float:  # type: ignore[no-untyped-def]
    fn()  # warm up (page faults, BLAS threads)
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def bench_evaluate(model, quick: bool) -> list[dict[str, float]]:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(0)
    rows = []
    for batch in (1, 10, 1000, 10000):
        w = rng.random((batch, model.n_shapes)).astype(np.float32)
        repeat = 20 if batch <= 10 else 3
        if batch < 10000:
            out = np.empty((batch, model.n_vertices, 3), dtype=np.float32)
            t = timed(lambda w=w, out=out: model.evaluate(w, gaze=False, out=out), repeat)
            t_gaze = timed(lambda w=w, out=out: model.evaluate(w, out=out), repeat)
            tracemalloc.start()
            model.evaluate(w)
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            mode = "evaluate (output preallocated)"
        else:
            # 10,000 faces are 3.2 GB of vertices: stream them in chunks instead.
            def stream(w=w, gaze=False) -> None:  # type: ignore[no-untyped-def]
                for _ in model.evaluate_chunks(w, gaze=gaze):
                    pass

            t = timed(stream, 1 if quick else 2)
            t_gaze = timed(lambda: stream(gaze=True), 1 if quick else 2)
            tracemalloc.start()
            stream()
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            mode = "evaluate_chunks (streamed, 256 a chunk)"
        n_loop = min(batch, 10 if quick else 100)
        t_loop = (
            timed(lambda n=n_loop, w=w: loop_blend(model.neutral, model.deltas, w[:n]), 1)
            * batch
            / n_loop
        )
        rows.append(
            {
                "batch": batch,
                "mode": mode,
                "seconds": t,
                "faces_per_s": batch / t,
                "faces_per_s_with_gaze": batch / t_gaze,
                "loop_faces_per_s": batch / t_loop,
                "speedup_vs_loop": t_loop / t,
                "loop_faces_measured": n_loop,
                "peak_mb": peak / 1e6,
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    parser.add_argument("--json", type=Path, help="also write the figures as JSON")
    parser.add_argument(
        "--only",
        nargs="*",
        choices=["cli", "gltf", "render", "viewer", "appearance", "correct", "simulate", "study"],
        help="run only these sections after the model benchmarks",
    )
    args = parser.parse_args()

    from emogen.model import load_model

    path = model_path()
    print(f"EmoGen benchmarks  model={path}  cores={os.cpu_count()}")
    results: dict[str, object] = {}

    load = bench_load(path)
    results["load"] = load
    print("\n== model load (fresh process each) ==")
    print(f"cold (parse 78 OBJ files)   {load['cold_load_s'] * 1000:8.1f} ms")
    print(
        f"warm (compiled cache)       {load['warm_load_s'] * 1000:8.1f} ms   (+ import {load['warm_import_s'] * 1000:.0f} ms)"
    )

    model = load_model(path)
    rows = bench_evaluate(model, args.quick)
    results["evaluate"] = rows
    print("\n== evaluate: faces per second (float32, all 26,719 vertices) ==")
    print(
        f"{'batch':>6} {'faces/s':>10} {'+gaze':>10} {'loop f/s':>10} {'speedup':>8} {'peak MB':>8}  mode"
    )
    for r in rows:
        print(
            f"{r['batch']:>6} {r['faces_per_s']:>10.0f} {r['faces_per_s_with_gaze']:>10.0f} "
            f"{r['loop_faces_per_s']:>10.1f} {r['speedup_vs_loop']:>7.0f}x {r['peak_mb']:>8.0f}  {r['mode']}"
        )
    print(
        "(loop = per-shape Python loop `for k: v += w[k] * delta[k]`, timed on "
        f"{rows[-1]['loop_faces_measured']} faces of each batch in this run and scaled)"
    )

    from benchmarks import (
        bench_appearance,
        bench_cli,
        bench_correct,
        bench_gltf,
        bench_plain_ga,
        bench_render,
        bench_simulate,
        bench_step,
        bench_study,
        bench_viewer,
    )

    sections = {
        "cli": lambda: bench_cli.run(3 if args.quick else 5),
        "gltf": lambda: bench_gltf.run(model),
        "render": lambda: bench_render.run(model),
        "viewer": lambda: bench_viewer.run(model),
        "appearance": lambda: bench_appearance.run(model, path),
        "correct": lambda: bench_correct.run(
            model, 2_000 if args.quick else 10_000, model_path=path
        ),
        "simulate": lambda: bench_simulate.run(model),
        "plain_ga": lambda: bench_plain_ga.run(model.rig),
        "study": lambda: bench_study.run(),
        "step": lambda: bench_step.run(4 if args.quick else 8),
    }
    for name, run in sections.items():
        if args.only and name not in args.only:
            continue
        results[name] = run()

    if args.json:
        args.json.write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    sys.path.insert(0, str(REPO))
    main()
