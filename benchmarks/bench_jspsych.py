"""The jsPsych plugin: its bundle's size, and a jsPsych page's time to show its first ten faces
(an evolve trial first, against ``emogen serve`` on this machine; headless Chromium with
SwiftShader, as the browser tests; a fresh browser context each time, so nothing is cached).
Target: ready < 3 s, like emogen's own page (bench_viewer.py).

``python benchmarks/bench_jspsych.py [--runs 5] [--json FILE]`` (model: $EMOGEN_MODEL).
"""

from __future__ import annotations

import argparse
import gzip
import json
import statistics
import sys
import tempfile
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.web.viewer_site import CHROMIUM, CHROMIUM_ARGS  # noqa: E402

from benchmarks.bench_study import ServerProcess, write_study_toml  # noqa: E402
from benchmarks.jspsych_site import PLUGIN, ExperimentSite, build_plugin, one_trial_page  # noqa: E402
from benchmarks.run import model_path  # noqa: E402

STUDY: dict[str, Any] = {
    "name": "bench-jspsych",
    "emotions": ["happy"],
    "identities": ["female-medium"],
    "blocks": [{"task": "evolve"}],
}


def bundle_sizes() -> dict[str, dict[str, int]]:
    """Bytes of each file the package ships, raw and gzipped (what a CDN sends)."""
    build_plugin()
    out = {}
    for name in ("index.browser.min.js", "index.js", "emogen.css"):
        data = (PLUGIN / "dist" / name).read_bytes()
        out[name] = {"bytes": len(data), "gzip_bytes": len(gzip.compress(data, 9))}
    return out


def first_faces(runs: int) -> list[float]:
    """Per run: navigation → ten faces drawn (s, the page's clock): scripts, jsPsych, the
    session made, the identity's GLB read, ten faces drawn."""
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        site = ExperimentSite(folder / "site")
        config = write_study_toml({**STUDY, "embed_origins": [site.origin]}, folder / "s.toml")
        srv = ServerProcess(
            config, f"sqlite:///{folder / 'db.sqlite'}", Path(model_path()), folder / "server.log"
        ).start()
        page_url = site.add("bench.html", one_trial_page(srv.url, [{"task": "evolve"}]))
        ready: list[float] = []
        try:
            with sync_playwright() as p:
                browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
                for k in range(runs + 1):  # the first warms the server's GLB cache: not counted
                    context = browser.new_context(viewport={"width": 1366, "height": 768})
                    page = context.new_page()
                    page.goto(f"{page_url}?PROLIFIC_PID=bench-{k}")
                    page.wait_for_function("window.firstFacesAt !== undefined", timeout=120_000)
                    at = page.evaluate("window.firstFacesAt") / 1000
                    if k:
                        ready.append(at)
                    context.close()
                browser.close()
        finally:
            srv.stop()
            site.close()
        return ready


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    sizes = bundle_sizes()
    for name, s in sizes.items():
        print(f"{name:24s} {s['bytes'] / 1e3:8.1f} kB   gzip {s['gzip_bytes'] / 1e3:7.1f} kB")
    r = first_faces(args.runs)
    print(
        f"first ten faces shown    median {statistics.median(r):.2f} s  (min {min(r):.2f}, max "
        f"{max(r):.2f}; {len(r)} fresh page loads; target < 3 s)"
    )
    if args.json:
        args.json.write_text(json.dumps({"sizes": sizes, "ready_s": r}, indent=2))


if __name__ == "__main__":
    main()
