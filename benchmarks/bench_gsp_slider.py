"""The GSP slider's frame rate: a participant's page (``emogen serve``, SQLite) at 1366×768 in
headless Chromium with software GL (SwiftShader, as the browser tests), the face of a GSP
trial (the ``female-medium`` identity, corrected faces, 41 positions) shown as the slider moves.
The page moves the slider one position per animation frame (an ``input`` event: the component
shows the face of that position) and counts the animation frames per second it kept up
(``requestAnimationFrame``), twice:

* ``from the opening``: for ``--seconds`` from the moment the trial's face is shown, while the
  viewer is still drawing the positions' frames ahead (viewer/kept.js: a position not yet kept
  is drawn live when shown, then kept); then the seconds from the opening until every
  position's frame is kept;
* ``all kept``: for ``--seconds`` once every position's frame is kept (played by a 2D canvas).

With each: the time one input event's update takes, the CPU a frame cost Chromium's GPU process
(SwiftShader draws there) and the page, which the load does not stretch, and the machine's load
average (it is shared). Target: ≥ 30 frames/s at 1366×768 (issue #43).

Measured on the shared 2-core VM (docs/study.md): drawn live on every input event (before the
kept frames), 7.6–11.8 frames/s at load averages 1.5–12 (80–92 ms of GPU-process CPU a frame);
from kept frames, all kept, 60.0, 44.3, 29.5 and 15.5 frames/s at load averages 24–31 and 59.9
at load 5 (2–3 ms of GPU-process CPU and 3–5 ms of page a frame; from the opening 33.8 at load
5), every frame kept 6–15 s after the opening.

    python -m benchmarks.bench_gsp_slider [--seconds 5]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Any

from benchmarks.bench_render import CHROMIUM
from benchmarks.bench_study import ServerProcess, write_study_toml
from benchmarks.bench_viewer import ARGS, chromium_cpu_s

TARGET_FPS = 30.0
STUDY: dict[str, Any] = {
    "name": "gsp-bench",
    "emotions": ["happy"],
    "identities": ["female-medium"],
    "seed": 1,
    "blocks": [{"task": "gsp", "chains": 2, "iterations": 1, "steps": 41}],
}

# One slider position per animation frame for ``ms``; each input event's update timed.
SWEEP = """async (ms) => {
  const slider = document.getElementById("gsp-slider");
  const steps = Number(slider.max) + 1;
  const updates = [];
  let frames = 0, k = 0;
  const t0 = performance.now();
  await new Promise((resolve) => {
    const frame = () => {
      const now = performance.now();
      if (now - t0 >= ms) return resolve();
      k = (k + 1) % (2 * (steps - 1));
      slider.value = String(k < steps ? k : 2 * (steps - 1) - k);
      const u0 = performance.now();
      slider.dispatchEvent(new Event("input", { bubbles: true }));
      updates.push(performance.now() - u0);
      frames += 1;
      requestAnimationFrame(frame);
    };
    requestAnimationFrame(frame);
  });
  updates.sort((a, b) => a - b);
  return { frames, seconds: (performance.now() - t0) / 1000,
           median_ms: updates[Math.floor(updates.length / 2)],
           p95_ms: updates[Math.floor(0.95 * (updates.length - 1))] };
}"""


KEPT = "() => window.emogenStudy.keptFrames().find(Boolean) ?? null"
SINCE_SHOWN = "() => (performance.now() - window.emogenStudy.shownAt) / 1000"


def sweep(page: Any, seconds: float) -> dict[str, Any]:
    """The slider swept for ``seconds``: frames/s, the update's times and the CPU a frame."""
    import os

    load = os.getloadavg()[0]
    cpu0 = chromium_cpu_s()
    out = page.evaluate(SWEEP, seconds * 1000)
    cpu1 = chromium_cpu_s()
    cpu = {f"{k}_cpu_ms": 1000 * (cpu1[k] - cpu0[k]) / max(out["frames"], 1) for k in cpu0}
    load = max(load, os.getloadavg()[0])
    return {"fps": out["frames"] / out["seconds"], "load": load, **out, **cpu}


def measure(model: Path, seconds: float, size: tuple[int, int]) -> dict[str, Any]:
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        config = write_study_toml(STUDY, folder / "gsp.toml")
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
                page.wait_for_selector(
                    "#gsp-slider:not([disabled])", state="visible", timeout=120_000
                )
                while not page.evaluate("() => window.emogenStudy.ready"):
                    page.wait_for_timeout(20)
                display = page.evaluate("() => window.emogenStudy.display")
                began = page.evaluate(SINCE_SHOWN)
                opening = sweep(page, seconds)
                opening["began_s"] = began
                opening["kept"] = page.evaluate(KEPT)
                page.wait_for_function(f"() => ({KEPT})()?.complete", timeout=300_000, polling=50)
                opening["all_kept_s"] = page.evaluate(SINCE_SHOWN)
                kept = sweep(page, seconds)
                kept["kept"] = page.evaluate(KEPT)
                browser.close()
        finally:
            srv.stop()
    return {"display": display, "opening": opening, "kept": kept}


def line(what: str, r: dict[str, Any]) -> str:
    return (
        f"  {what}: {r['fps']:.1f} frames/s over {r['seconds']:.1f} s ({r['frames']} slider "
        f"moves, load average <= {r['load']:.1f}); one input event's update: median "
        f"{r['median_ms']:.2f} ms, p95 {r['p95_ms']:.2f} ms; CPU per frame: GPU process "
        f"{r['gpu_cpu_ms']:.0f} ms, page {r['page_cpu_ms']:.0f} ms; frames kept after it: "
        f"{r['kept']['kept']} of {r['kept']['of']}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--model", type=Path, default=None, help="ICT-FaceKit FaceXModel folder")
    args = parser.parse_args()
    import os

    model = args.model or Path(os.environ.get("EMOGEN_MODEL", "../shared/ict-facekit/FaceXModel"))
    size = (1366, 768)
    r = measure(model, args.seconds, size)
    fps = r["kept"]["fps"]
    print(f"GSP slider, {size[0]}x{size[1]}, {r['display']} (SwiftShader), 41 positions:")
    began = r["opening"]["began_s"]
    print(line(f"from the opening (+{began:.1f} s; frames still drawn ahead)", r["opening"]))
    print(f"  every position's frame kept {r['opening']['all_kept_s']:.1f} s after the opening")
    print(line("all kept", r["kept"]))
    verdict = "met" if fps >= TARGET_FPS else "NOT met"
    print(f"  target >= {TARGET_FPS:.0f} frames/s once kept: {verdict}")


if __name__ == "__main__":
    main()
