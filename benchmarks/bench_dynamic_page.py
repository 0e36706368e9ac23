"""The evolve page's frame rate with faces that move: a participant's page (``emogen serve``,
SQLite, an evolve block with ``dynamic = {}``, corrected faces) at 1366×768 in headless
Chromium with software GL (SwiftShader, as the browser tests), its ten tiles playing their
clips. For ``--seconds`` the page counts ``requestAnimationFrame`` callbacks and the viewer's
drawn frames (each: the ten faces' morph weights from their curves in one typed-array pass,
then the ten faces drawn); the figures are the frames per second drawn and the time between
frames (median, 95th percentile). The machine's load average is printed beside them (it is
shared). Target: ≥ 15 frames/s at 1366×768 on this machine's software GL (issue #44).

    python -m benchmarks.bench_dynamic_page [--seconds 5]
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path
from typing import Any

from benchmarks.bench_render import CHROMIUM
from benchmarks.bench_study import ServerProcess, write_study_toml
from benchmarks.bench_viewer import ARGS

TARGET_FPS = 15.0
STUDY: dict[str, Any] = {
    "name": "dynamic-bench",
    "emotions": ["happy"],
    "seed": 1,
    "blocks": [{"task": "evolve", "dynamic": {}}],
}

# Animation frames for ``ms``: their count and the gaps between them, and the clip times the
# tiles showed at the start and the end (that they play).
FRAMES = """async (ms) => {
  const gaps = [];
  let last = null;
  const before = window.emogenStudy.clipTimes();
  const t0 = performance.now();
  await new Promise((resolve) => {
    const frame = (now) => {
      if (last !== null) gaps.push(now - last);
      last = now;
      if (now - t0 >= ms) return resolve();
      requestAnimationFrame(frame);
    };
    requestAnimationFrame(frame);
  });
  gaps.sort((a, b) => a - b);
  return { frames: gaps.length, seconds: (performance.now() - t0) / 1000,
           median_ms: gaps[Math.floor(gaps.length / 2)],
           p95_ms: gaps[Math.floor(0.95 * (gaps.length - 1))],
           before, after: window.emogenStudy.clipTimes() };
}"""


def measure(model: Path, seconds: float, size: tuple[int, int]) -> dict[str, Any]:
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        config = write_study_toml(STUDY, folder / "dynamic.toml")
        srv = ServerProcess(
            config, f"sqlite:///{folder / 'db.sqlite'}", model, folder / "server.log"
        ).start()
        try:
            with sync_playwright() as p:
                browser = p.chromium.launch(executable_path=str(CHROMIUM), args=ARGS)
                page = browser.new_page(viewport={"width": size[0], "height": size[1]})
                page.goto(f"{srv.url}/?PROLIFIC_PID=bench")
                page.get_by_role("button", name="I agree").click()
                page.get_by_role("button", name="Begin").click()
                page.wait_for_selector("#motion", state="visible", timeout=120_000)
                while not page.evaluate("() => window.emogenStudy.ready"):
                    page.wait_for_timeout(100)
                display = page.evaluate("() => window.emogenStudy.display")
                page.wait_for_timeout(1000)  # the first frames (strains computed) pass
                out = page.evaluate(FRAMES, seconds * 1000)
                browser.close()
        finally:
            srv.stop()
    playing = sum(t is not None for t in out["after"])
    if playing != 10 or out["before"] == out["after"]:
        raise SystemExit(f"the tiles did not play: clip times {out['before']} → {out['after']}")
    return {"display": display, "fps": out["frames"] / out["seconds"], **out}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--model", type=Path, default=None, help="ICT-FaceKit FaceXModel folder")
    args = parser.parse_args()
    model = args.model or Path(os.environ.get("EMOGEN_MODEL", "../shared/ict-facekit/FaceXModel"))
    for size in ((1366, 768), (683, 384)):
        load = os.getloadavg()[0]
        r = measure(model, args.seconds, size)
        load = max(load, os.getloadavg()[0])
        met = "met" if r["fps"] >= TARGET_FPS else "NOT met"
        print(
            f"10 moving tiles, {size[0]}x{size[1]}, {r['display']} (SwiftShader), load average "
            f"<= {load:.1f}: {r['fps']:.1f} frames/s over {r['seconds']:.1f} s; between frames: "
            f"median {r['median_ms']:.1f} ms, p95 {r['p95_ms']:.1f} ms"
            + (f"; target >= {TARGET_FPS:.0f} frames/s: {met}" if size == (1366, 768) else "")
        )


if __name__ == "__main__":
    main()
