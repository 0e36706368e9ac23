"""Rendering: ms per 512² face offscreen, a 10-face contact sheet, GLB bytes on the wire, and —
when the viewer is built and Chromium is there — the browser page's time to ready."""

from __future__ import annotations

import functools
import gzip
import http.server
import shutil
import tempfile
import threading
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


def _page_ready(model: Any, tries: int = 3) -> float | None:  # type: ignore[no-untyped-def]
    """Seconds from navigation to window.emogenReady (ten faces drawn), best of ``tries``."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        return None
    if not (BUILD / "viewer.js").is_file() or not CHROMIUM.exists():
        return None
    from emogen.model.io.gltf import export_model_glb

    with tempfile.TemporaryDirectory() as tmp:
        for f in ("index.html", "viewer.css", "viewer.js"):
            shutil.copy(BUILD / f, Path(tmp) / f)
        export_model_glb(model, Path(tmp) / "face.glb")

        class Quiet(http.server.SimpleHTTPRequestHandler):
            def log_message(self, format: str, *args: Any) -> None:
                pass

        server = http.server.ThreadingHTTPServer(
            ("127.0.0.1", 0), functools.partial(Quiet, directory=tmp)
        )
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = f"http://127.0.0.1:{server.server_address[1]}/index.html"
        args = [
            "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
            "--disable-quic", "--no-first-run", "--disable-background-networking",
            "--disable-component-update", "--disable-sync",
        ]  # fmt: skip
        best = float("inf")
        try:
            with sync_playwright() as p:
                browser = p.chromium.launch(executable_path=str(CHROMIUM), args=args)
                for _ in range(tries):
                    context = browser.new_context(viewport={"width": 1400, "height": 700})
                    page = context.new_page()
                    t = time.perf_counter()
                    page.goto(url)
                    page.wait_for_function("window.emogenReady === true", polling=50)
                    best = min(best, time.perf_counter() - t)
                    context.close()
                browser.close()
        finally:
            server.shutdown()
    return best


def run(model) -> dict[str, float | None]:  # type: ignore[no-untyped-def]
    from emogen.model.io.gltf import export_model_glb
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

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "face.glb"
        export_model_glb(model, path)
        raw = path.read_bytes()
    wire = len(gzip.compress(raw, 9))
    ready = _page_ready(model)

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
    print(
        f"GLB for the viewer       {len(raw) / 1e6:7.2f} MB raw, {wire / 1e6:.2f} MB on the wire (gzip -9)"
    )
    if ready is not None:
        print(
            f"viewer page ready        {ready:7.2f} s   (ten faces, Chromium/SwiftShader; target < 3)"
        )
    else:
        print(
            "viewer page ready        (skipped: needs npm run build, Playwright and /usr/bin/chromium)"
        )
    return {
        "ms_per_face_512": one * 1000,
        "ms_per_face_512_batch": batch * 1000,
        "cpu_ms_per_face_512": cpu_per_face * 1000,
        "ms_png_encode_included": with_png * 1000,
        "context_ms": context_s * 1000,
        "sheet10_s": sheet_warm,
        "sheet10_cold_s": sheet_cold,
        "glb_raw_bytes": len(raw),
        "glb_gzip_bytes": wire,
        "page_ready_s": ready,
    }


if __name__ == "__main__":
    import sys

    sys.path.insert(0, str(REPO / "src"))
    from emogen.model import load_model

    run(load_model(sys.argv[1] if len(sys.argv) > 1 else None))
