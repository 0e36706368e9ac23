"""What a participant's browser loads: the textured GLB of an identity as the study serves it
(``emogen.web.assets.ModelGLBs``: mesh, morph targets, skin atlas and detail tile, gzip as
served) and the viewer page's time to ready with ten textured faces (headless Chromium with
SwiftShader, as the viewer tests). Targets: ≤ 4 MB on the wire, ready < 3 s."""

from __future__ import annotations

import functools
import gzip
import http.server
import os
import shutil
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from benchmarks.bench_render import BUILD, CHROMIUM

WIRE_TARGET_MB = 4.0
READY_TARGET_S = 3.0
ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def chromium_cpu_s() -> dict[str, float]:
    """CPU seconds (every thread, ``/proc/<pid>/task/*/schedstat``) of the Chromium processes
    this process started, by kind: ``gpu`` (the GPU process: SwiftShader draws there) and
    ``page`` (the renderers: the page's JavaScript). Read before and after a measurement, the
    difference is the work it cost, which a shared machine's load does not stretch as it
    stretches the wall-clock figures."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue
            children.setdefault(ppid, []).append(int(entry.name))
    out = {"gpu": 0.0, "page": 0.0}
    todo = list(children.get(os.getpid(), []))
    while todo:
        pid = todo.pop()
        todo += children.get(pid, [])
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_text()
        except OSError:
            continue
        kind = (
            "gpu" if "--type=gpu-process" in cmd else "page" if "--type=renderer" in cmd else None
        )
        if kind is None:
            continue
        for task in Path(f"/proc/{pid}/task").glob("*"):
            try:
                out[kind] += int((task / "schedstat").read_text().split()[0]) / 1e9
            except (OSError, ValueError, IndexError):
                continue
    return out


class _GzipHandler(http.server.SimpleHTTPRequestHandler):
    """Serves face.glb gzipped, as the study server does (Content-Encoding: gzip)."""

    def log_message(self, format: str, *args: Any) -> None:
        pass

    def do_GET(self) -> None:
        gz = Path(self.directory) / "face.glb.gz"
        if self.path.split("?")[0] != "/face.glb" or not gz.is_file():
            super().do_GET()
            return
        body = gz.read_bytes()
        self.send_response(200)
        self.send_header("Content-Type", "model/gltf-binary")
        self.send_header("Content-Encoding", "gzip")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)


def _page_ready(folder: str, tries: int) -> float | None:
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        return None
    if not (BUILD / "viewer.js").is_file() or not CHROMIUM.exists():
        return None
    server = http.server.ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(_GzipHandler, directory=folder)
    )
    threading.Thread(target=server.serve_forever, daemon=True).start()
    url = f"http://127.0.0.1:{server.server_address[1]}/index.html"
    best = float("inf")
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=str(CHROMIUM), args=ARGS)
            for _ in range(tries):
                context = browser.new_context(viewport={"width": 1400, "height": 700})
                page = context.new_page()
                t = time.perf_counter()
                page.goto(url)
                page.wait_for_function("window.emogenReady === true", polling=50)
                best = min(best, time.perf_counter() - t)
                if not page.evaluate("window.emogen.view?.textured === true"):
                    raise RuntimeError("the viewer did not draw textured faces")
                context.close()
            browser.close()
    finally:
        server.shutdown()
    return best


def run(model, identity: str = "generic", tries: int = 3) -> dict[str, float | None]:
    from emogen.web.assets import ModelGLBs

    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        glb = ModelGLBs(model, folder=Path(tmp) / "cache").path(identity)  # textures cached
        export_s = time.perf_counter() - t
        raw = glb.read_bytes()
        served = glb.with_suffix(".glb.gz").read_bytes()
        site = Path(tmp) / "site"
        site.mkdir()
        for f in ("index.html", "viewer.css", "viewer.js"):
            if (BUILD / f).is_file():
                shutil.copy(BUILD / f, site / f)
        shutil.copy(glb, site / "face.glb")
        (site / "face.glb.gz").write_bytes(served)
        ready = _page_ready(str(site), tries)
    gzip9 = len(gzip.compress(raw, 9))
    print(f"\n== participant's browser: textured GLB of '{identity}' and ten faces ==")
    print(
        f"GLB + textures           {len(raw) / 1e6:7.2f} MB raw, {len(served) / 1e6:.2f} MB on the "
        f"wire (gzip as served; -9: {gzip9 / 1e6:.2f}; target <= {WIRE_TARGET_MB:.0f})   "
        f"export {export_s:.1f} s"
    )
    if ready is not None:
        print(
            f"viewer page ready        {ready:7.2f} s   (ten textured faces, Chromium/SwiftShader,"
            f" GLB gzipped; target < {READY_TARGET_S:.0f})"
        )
    else:
        print("viewer page ready        (skipped: needs npm run build, Playwright and Chromium)")
    return {
        "raw_bytes": len(raw),
        "wire_bytes": len(served),
        "gzip9_bytes": gzip9,
        "export_s": export_s,
        "page_ready_s": ready,
    }
