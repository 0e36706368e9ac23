"""Rendering: ms per 512² face offscreen and a 10-face contact sheet (the browser side:
bench_viewer.py)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
BUILD = REPO / "src" / "emogen" / "web" / "static" / "build"
CHROMIUM = Path("/usr/bin/chromium")


def _faces(model: Any, n: int) -> np.ndarray:  # type: ignore[no-untyped-def]
    """n expressive faces: 3-6 random genes each (seeded)."""
    rng = np.random.default_rng(5)
    genes = [g.name for g in model.rig.genes]
    out = []
    for _ in range(n):
        pick = rng.choice(genes, size=rng.integers(3, 7), replace=False)
        out.append(model.rig.weights_from_names({g: float(rng.uniform(0.3, 1.0)) for g in pick}))
    return np.asarray(out)


def _best(fn: Any, repeat: int) -> float:  # type: ignore[no-untyped-def]
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def run(model) -> dict[str, float | None]:  # type: ignore[no-untyped-def]
    from emogen.render.images import png_bytes
    from emogen.render.renderer import Renderer

    w10 = _faces(model, 10)
    t = time.perf_counter()
    renderer = Renderer(model, size=512)
    context_s = time.perf_counter() - t
    renderer.render(w10[:1])  # warm up
    one = _best(lambda: renderer.render(w10[:1]), 5)
    batch = _best(lambda: renderer.render(w10), 3) / 10
    cpu0 = time.process_time()
    renderer.render(w10)
    cpu_per_face = (time.process_time() - cpu0) / 10  # all threads: what other load can't hide
    with_png = _best(lambda: png_bytes(renderer.render(w10[:1])[0]), 3)
    renderer.close()

    def sheet() -> None:
        with Renderer(model, size=256) as r:
            png_bytes(r.sheet(w10))

    sheet_cold = _best(sheet, 2)
    with Renderer(model, size=256) as r:
        r.sheet(w10[:1])
        sheet_warm = _best(lambda: png_bytes(r.sheet(w10)), 3)

    print("\n== rendering (offscreen: moderngl + EGL, llvmpipe; 2× supersampling) ==")
    print(
        f"one 512² face            {one * 1000:7.1f} ms   (with PNG encoding: {with_png * 1000:.1f} ms)"
    )
    print(
        f"512² faces in a batch    {batch * 1000:7.1f} ms per face   (target ≤ 80; "
        f"CPU time {cpu_per_face * 1000:.0f} ms over both cores)"
    )
    print(f"OpenGL context + setup   {context_s * 1000:7.1f} ms   (once per Renderer)")
    print(
        f"10-face contact sheet    {sheet_warm:7.2f} s warm, {sheet_cold:.2f} s with a new "
        "context (256² faces, labels, PNG; target < 1)"
    )
    print("(GLB size and page-ready time of the textured viewer: section 'viewer')")
    return {
        "ms_per_face_512": one * 1000,
        "ms_per_face_512_batch": batch * 1000,
        "cpu_ms_per_face_512": cpu_per_face * 1000,
        "ms_png_encode_included": with_png * 1000,
        "context_ms": context_s * 1000,
        "sheet10_s": sheet_warm,
        "sheet10_cold_s": sheet_cold,
    }


if __name__ == "__main__":
    import sys

    sys.path.insert(0, str(REPO / "src"))
    from emogen.model import load_model

    run(load_model(sys.argv[1] if len(sys.argv) > 1 else None))
