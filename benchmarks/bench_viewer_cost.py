"""Where a frame of the browser viewer goes on software GL, and what the ways left to a faster
page could gain: the viewer page (``viewer/index.html``, the ``generic`` identity's textured GLB
as the study serves it) in headless Chromium with SwiftShader at 1366×768, one face at the GSP
page's size (445×445 pixels: ``min(58vh, 92vw, 560px)``) and ten tiles of 250×250. Each row
redraws for ``--seconds`` once per animation frame, the face's weights changing every frame (a
sweep of 30 shapes, as a slider or a clip moves them), and prints the frame rate and the CPU a
frame cost Chromium's GPU process (SwiftShader draws there) and the page, beside the load
average (the machine is shared; CPU time is what its load does not stretch):

* ``as drawn``: the viewer as it is;
* ``32×32 pixels``: the same faces in 32×32-pixel slots: the vertex and triangle work, almost no
  pixels;
* ``skin alone`` and ``skin, its textures compiled out``: the skin primitive only, and with
  shade.glsl's skin section (atlas, micro-relief, wrinkles) compiled out: what the skin's
  shading costs (a measurement only: that shader is not the stimulus);
* ``visible triangles only`` (option 1 of issue #43's note: drop what the camera never sees): the
  triangles that showed in a triangle-ID buffer over ``--samples`` faces (every target alone at
  weight 1, then random sparse faces), and ``--rings`` rings of neighbours, drawn instead of all; its pixels
  compared with the full draw's over eight other random faces. This identity, framing and
  camera only, and shapes sampled rather than bounded: an estimate of the gain, not a safe
  culling set;
* ``pre-rendered frames``: each face's frames captured once from the canvas (ImageBitmap) and
  shown by a 2D canvas's drawImage: the cost of playing frames rendered ahead.

Measured on the shared 2-core VM (docs/render.md, load average 8–10): the GSP face 87 ms of
GPU-process CPU a frame, 26 in 32×32 slots, 64 with 46 % of the triangles, 11 played from
frames rendered ahead; ten tiles 558, 230, 292 and 61 ms.

    python -m benchmarks.bench_viewer_cost [--seconds 3] [--samples 200] [--rings 1]
"""

from __future__ import annotations

import argparse
import functools
import http.server
import os
import shutil
import sys
import tempfile
import threading
from pathlib import Path
from typing import Any

from benchmarks.bench_render import BUILD, CHROMIUM
from benchmarks.bench_viewer import ARGS, _GzipHandler, chromium_cpu_s

SCENES = {"GSP face 445x445": (1, 445), "ten tiles 250x250": (10, 250)}
JS = Path(__file__).with_name("viewer_cost.js")


def _site(folder: Path, model_path: str | None) -> None:
    from emogen.model import load_model
    from emogen.web.assets import ModelGLBs

    glb = ModelGLBs(load_model(model_path)).path("generic")
    for f in ("index.html", "viewer.css", "viewer.js"):
        shutil.copy(BUILD / f, folder / f)
    shutil.copy(glb, folder / "face.glb")
    shutil.copy(glb.with_suffix(".glb.gz"), folder / "face.glb.gz")


def _row(name: str, r: dict[str, Any], c0: dict[str, float], c1: dict[str, float]) -> str:
    frames = max(int(r["frames"]), 1)
    gpu = 1000 * (c1["gpu"] - c0["gpu"]) / frames
    page = 1000 * (c1["page"] - c0["page"]) / frames
    note = f"   {r['note']}" if r.get("note") else ""
    return (
        f"  {name:38s} {r['frames'] / r['seconds']:6.1f} frames/s   GPU process {gpu:6.1f} ms"
        f"   page {page:5.1f} ms   load {os.getloadavg()[0]:4.1f}{note}"
    )


def measure(folder: Path, seconds: float, samples: int, rings: int) -> None:
    from playwright.sync_api import sync_playwright

    server = http.server.ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(_GzipHandler, directory=str(folder))
    )
    threading.Thread(target=server.serve_forever, daemon=True).start()
    base = f"http://127.0.0.1:{server.server_address[1]}/index.html"
    script = JS.read_text()
    ms = seconds * 1000
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=str(CHROMIUM), args=ARGS)
            for scene, (faces, size) in SCENES.items():
                print(f"{scene}, 1366x768, SwiftShader:")
                for label, px in (("as drawn", size), ("32x32 pixels", 32)):
                    page = browser.new_page(viewport={"width": 1366, "height": 768})
                    page.goto(f"{base}?faces={faces}&size={px}&columns=5")
                    page.wait_for_function("window.emogenReady === true", polling=50)
                    if page.evaluate("window.emogen.mode") != "webgl":
                        raise SystemExit("the viewer did not start WebGL")
                    page.add_script_tag(content=script)
                    rows = [(label, "sweep", {})]
                    if px == size:
                        rows += [
                            ("skin alone", "sweep", {"only": 0}),
                            ("skin, its textures compiled out", "sweep", {"only": 0, "plain": 1}),
                            (
                                "visible triangles only",
                                "cull",
                                {"samples": samples, "rings": rings},
                            ),
                            ("pre-rendered frames", "prerendered", {}),
                        ]
                    for name, fn, opts in rows:
                        note = ""
                        if fn == "cull":  # made first, then drawn as the others
                            note = page.evaluate("(a) => window.viewerCost.cull(a)", opts)
                            fn, opts = "sweep", {}
                        c0 = chromium_cpu_s()
                        r = page.evaluate(f"(a) => window.viewerCost.{fn}(a)", {"ms": ms, **opts})
                        c1 = chromium_cpu_s()
                        print(_row(name, {"note": note, **r}, c0, c1), flush=True)
                        page.evaluate("window.viewerCost.uncull()")
                    page.close()
            browser.close()
    finally:
        server.shutdown()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--samples", type=int, default=200, help="faces for the ID buffer")
    parser.add_argument("--rings", type=int, default=1, help="rings of neighbours kept")
    parser.add_argument("--model", default=None, help="ICT-FaceKit FaceXModel folder")
    args = parser.parse_args()
    if not (BUILD / "viewer.js").is_file() or not CHROMIUM.exists():
        sys.exit("needs the viewer bundle (make setup) and Debian's Chromium")
    with tempfile.TemporaryDirectory() as tmp:
        _site(Path(tmp), args.model or os.environ.get("EMOGEN_MODEL"))
        measure(Path(tmp), args.seconds, args.samples, args.rings)


if __name__ == "__main__":
    main()
