"""One participant through the whole example design (examples/published-design.toml) in
Debian's Chromium (Playwright, SwiftShader WebGL as the browser tests): per-step times.

``python benchmarks/bench_design_walk.py [--config FILE] [--phone] [--json FILE]`` starts ``emogen serve``
(SQLite in a temporary folder, model: $EMOGEN_MODEL), opens the study as participant
``walk-1``, and answers every screen the study shows: evolve rounds (faces 1 and 2, next),
ratings (5), categorise trials (the first label, intensity and confidence 4). For every step it
prints

- ``server_ms``: the server's own time for the step request (its ``Server-Timing`` header:
  request in → response out, database commit included),
- ``client_ms``: the page's time from the click that sends the step to the next screen ready
  (faces drawn: ``window.emogenStudy.ready``),
- ``glb_ms``: time spent in that interval fetching a face model (GLB) of an identity,
- ``ready_ms``: the page's own ready time of the next screen (``window.emogenStudy.loadMs``:
  the step's answer, after any pause between trials, to the faces drawn — the load time the
  page reports to the server),
- the progress line (trial, round, part) and the 1-minute load average when the step ended,

and marks the first step of each new identity (the block switch), whose times are compared
with the median step of the block before; then every face model the page built (the 3D
display's record: ahead of its trial or when shown, download/parse/upload times). ``--phone``:
a 360×640 touch screen (device pixel ratio 2) instead of a 1366×768 desktop. The machine's load
is printed beside every figure: on a shared machine the client time is mostly the load.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.web.viewer_site import CHROMIUM, CHROMIUM_ARGS  # noqa: E402

from benchmarks.bench_study import ServerProcess  # noqa: E402
from benchmarks.run import model_path  # noqa: E402

DESIGN = REPO / "examples" / "published-design.toml"
STEP_TIMEOUT_S = 300.0


#: The page's time fetching face models (GLB) since ``since`` (its performance.now()), from
#: the browser's resource timing (cleared after each step: its buffer is bounded).
GLB_MS = """(since) => {
  const spans = performance.getEntriesByType("resource").filter((e) => e.name.endsWith(".glb"));
  performance.clearResourceTimings();
  return spans.reduce((ms, e) => ms + Math.max(0, e.responseEnd - Math.max(e.startTime, since)), 0);
}"""


def wait_ready(page: Any, timeout: float = STEP_TIMEOUT_S) -> str:
    """Poll (no eval in the page: its CSP forbids it) until a screen is ready; its name."""
    from playwright.sync_api import Error

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            got = page.evaluate(
                "() => window.emogenStudy && window.emogenStudy.ready"
                " ? window.emogenStudy.stage : ''"
            )
        except Error as exc:  # the page navigated while asked: ask the new page
            if "context was destroyed" not in str(exc) and "navigat" not in str(exc):
                raise
            got = ""
        if got:
            return str(got)
        page.wait_for_timeout(20)
    raise TimeoutError(f"no screen ready after {timeout:.0f} s")


def answer(page: Any, stage: str) -> None:
    """The participant's answer to the screen shown, ending in the click that sends it."""
    if stage == "trial":
        page.click("#grid > .cell:nth-child(1) .face")
        page.click("#grid > .cell:nth-child(2) .face")
        page.click("#next")
    elif stage == "rating":
        page.get_by_label("5", exact=True).check()
        page.click("#rate")
    elif stage == "categorise":
        page.click("#label-buttons button:nth-child(1)")
        for scale in ("#intensity-scale", "#confidence-scale"):
            if page.is_visible(scale):
                page.locator(scale).get_by_label("4", exact=True).check()
        page.click("#answer")
    else:
        raise RuntimeError(f"the walk does not know the screen '{stage}'")


PHONE = {
    "viewport": {"width": 360, "height": 640},
    "device_scale_factor": 2,
    "is_mobile": True,
    "has_touch": True,
}
DESKTOP = {"viewport": {"width": 1366, "height": 768}}


def walk(url: str, pid: str, device: dict[str, Any]) -> tuple[list[dict[str, Any]], list[Any]]:
    from playwright.sync_api import sync_playwright

    steps: list[dict[str, Any]] = []
    answers: list[tuple[float, str]] = []  # per step response: server ms, next identity

    def on_response(response: Any) -> None:
        if response.request.method == "POST" and response.url.endswith("/step"):
            timing = response.headers.get("server-timing", "")
            ms = float(timing.split("dur=")[1]) if "dur=" in timing else float("nan")
            try:
                trial = response.json().get("trial") or {}
            except Exception:  # an error page: no identity
                trial = {}
            answers.append((ms, str(trial.get("identity") or "")))

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        page = browser.new_context(**device).new_page()
        page.on("response", on_response)
        page.on("dialog", lambda d: d.accept())
        page.goto(f"{url}/?PROLIFIC_PID={pid}")
        page.get_by_role("button", name="I agree").click()
        wait_ready(page)
        page.get_by_role("button", name="Begin").click()
        stage = wait_ready(page)
        while stage != "done":
            progress = " ".join(page.inner_text("#progress").split())
            sent = len(answers)
            answer(page, stage)
            start = time.monotonic()
            page_start = page.evaluate("() => performance.now()")
            # the page still says ready until the step's answer arrives: wait for the next
            # screen's progress line (or the end), then for its faces; the transition screen
            # between trials (not ready: no faces) is part of the step
            while time.monotonic() - start < STEP_TIMEOUT_S and progress == " ".join(
                page.inner_text("#progress").split()
            ):
                if page.evaluate("() => window.emogenStudy.stage") == "done":
                    break
                page.wait_for_timeout(10)
            next_stage = wait_ready(page)
            end = time.monotonic()
            deadline = time.monotonic() + 10
            while len(answers) <= sent and time.monotonic() < deadline:
                page.wait_for_timeout(10)
            ms, ident = answers[sent] if len(answers) > sent else (float("nan"), "")
            steps.append(
                {
                    "step": len(steps) + 1,
                    "screen": stage,
                    "progress": progress,
                    "server_ms": ms,
                    "next_identity": ident,
                    "client_ms": (end - start) * 1000,
                    "glb_ms": page.evaluate(GLB_MS, page_start),
                    "ready_ms": page.evaluate("() => window.emogenStudy.loadMs"),
                    "load1": os.getloadavg()[0],
                }
            )
            stage = next_stage
        loads = page.evaluate("() => window.emogenStudy.loads.map((l) => ({...l}))")
        browser.close()
    return steps, loads


def print_table(steps: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The per-step table; the steps whose next screen shows another identity (a block
    switch), each with the median step of the screens before it."""
    print(
        f"{'step':>4} {'screen':<10} {'server ms':>9} {'client ms':>9} {'ready ms':>8} "
        f"{'glb ms':>7} {'load1':>5}  progress → next screen's identity"
    )
    switches = []
    last = ""  # the identity of the last screen shown
    for i, s in enumerate(steps):
        switch = s["screen"] != "categorise" and last not in ("", s["next_identity"])
        last = s["next_identity"] or last
        mark = "  <- identity switch" if switch else ""
        print(
            f"{s['step']:>4} {s['screen']:<10} {s['server_ms']:>9.1f} {s['client_ms']:>9.0f} "
            f"{s['ready_ms']:>8.0f} {s['glb_ms']:>7.0f} {s['load1']:>5.2f}  {s['progress']} → "
            f"{s['next_identity'] or '-'}{mark}"
        )
        if switch and i:
            block = steps[max(0, i - 20) : i]
            switches.append(
                {
                    "step": s["step"],
                    "to": s["next_identity"],
                    "server_ms": s["server_ms"],
                    "client_ms": s["client_ms"],
                    "ready_ms": s["ready_ms"],
                    "glb_ms": s["glb_ms"],
                    "load1": s["load1"],
                    "median_server_ms_20_before": statistics.median(t["server_ms"] for t in block),
                    "median_client_ms_20_before": statistics.median(t["client_ms"] for t in block),
                    "median_ready_ms_20_before": statistics.median(t["ready_ms"] for t in block),
                }
            )
    return switches


def cold_cache(tmp: Path) -> Path:
    """A cache folder with this machine's compiled model and correctives but no GLB."""
    from emogen.model.io.cache import cache_root

    cache = tmp / "cache"
    cache.mkdir()
    for entry in cache_root().iterdir():
        if entry.name != "glb":
            (cache / entry.name).symlink_to(entry)
    return cache


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", type=Path, default=DESIGN)
    parser.add_argument("--json", type=Path, default=None, help="Also write the steps here.")
    parser.add_argument(
        "--cold-glb",
        action="store_true",
        help="No identity's 3D model (GLB) made yet, as on a study's first start after an "
        "install or a new identity: the server's cache without its glb folder.",
    )
    parser.add_argument("--phone", action="store_true", help="A phone's screen (360x640, touch).")
    args = parser.parse_args()
    if not Path(CHROMIUM).exists():
        sys.exit(f"needs Debian's Chromium at {CHROMIUM}: apt-get install chromium")
    with tempfile.TemporaryDirectory() as tmp:
        env = {"EMOGEN_CACHE_DIR": str(cold_cache(Path(tmp)))} if args.cold_glb else {}
        server = ServerProcess(
            args.config,
            f"sqlite:///{Path(tmp) / 'walk.sqlite'}",
            Path(model_path()),
            Path(tmp) / "server.log",
            env=env,
        )
        began = time.monotonic()
        server.start(timeout=300)
        started_s = time.monotonic() - began
        try:
            wall = time.monotonic()
            steps, loads = walk(server.url, "walk-1", PHONE if args.phone else DESKTOP)
            wall = time.monotonic() - wall
        finally:
            server.stop()
    cold = " (no GLB made yet)" if args.cold_glb else ""
    print("phone 360x640" if args.phone else "desktop 1366x768")
    print(f"server start{cold} {started_s:.1f} s; load average at the end {os.getloadavg()}")
    switches = print_table(steps)
    server_times = [s["server_ms"] for s in steps]
    client = [s["client_ms"] for s in steps]
    ready = [s["ready_ms"] for s in steps]
    print(
        f"{len(steps)} steps in {wall:.0f} s; server ms median {statistics.median(server_times):.1f} "
        f"max {max(server_times):.1f}; client ms median {statistics.median(client):.0f} "
        f"max {max(client):.0f}; page ready ms median {statistics.median(ready):.0f} "
        f"max {max(ready):.0f}; load1 {min(s['load1'] for s in steps):.2f}–"
        f"{max(s['load1'] for s in steps):.2f}"
    )
    for s in switches:
        print(
            f"switch to {s['to']} at step {s['step']}: server {s['server_ms']:.1f} ms (median "
            f"of the 20 before {s['median_server_ms_20_before']:.1f}), client "
            f"{s['client_ms']:.0f} ms (median {s['median_client_ms_20_before']:.0f}), of "
            f"which the GLB fetch {s['glb_ms']:.0f} ms; page ready {s['ready_ms']:.0f} ms "
            f"(median {s['median_ready_ms_20_before']:.0f}); "
            f"load1 {s['load1']:.2f}"
        )
    for m in loads:
        when = "ahead" if m["ahead"] else "shown"
        print(
            f"model {m['url'].rsplit('/', 1)[-1]} built {when}: {m['total_ms']:.0f} ms (download "
            f"{m['fetch_ms']:.0f}, parse {m['gltf_ms']:.0f}, attributes {m['attributes_ms']:.0f}, "
            f"strain {m['strain_ms']:.0f}, shaders {m['compile_ms']:.0f}, first draw "
            f"{m['first_render_ms']:.0f})"
        )
    if args.json is not None:
        out = {"steps": steps, "switches": switches, "loads": loads}
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
