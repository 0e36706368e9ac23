"""A lab's jsPsych experiment site for the plugin's browser test and benchmark: a plain
http.server (another origin than the study server) serving jsPsych and its survey-text plugin
from node_modules, the built emogen plugin, and pages — the README's example page with its CDN
addresses pointed at these copies and its server at a running ``emogen serve``.
"""

from __future__ import annotations

import functools
import http.server
import json
import re
import shutil
import subprocess
import threading
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PLUGIN = REPO / "packages" / "jspsych-plugin-emogen"
BUNDLE = PLUGIN / "dist" / "index.browser.min.js"
NODE_MODULES = REPO / "node_modules"
#: The README example's addresses (jsPsych's CDN; the plugin's copy on the lab's own site, as
#: its README says to put it) → this site's copies.
VENDOR = {
    "https://unpkg.com/jspsych@8.3.0/": NODE_MODULES / "jspsych",
    "https://unpkg.com/@jspsych/plugin-survey-text@2.1.1/": NODE_MODULES
    / "@jspsych"
    / "plugin-survey-text",
    "/lib/jspsych-plugin-emogen/": PLUGIN,
}


def _sources() -> list[Path]:
    web = REPO / "src" / "emogen" / "web"
    return [
        PLUGIN / "build.mjs",
        *(PLUGIN / "src").glob("*"),
        *(web / "static").glob("*.js"),
        *(web / "static" / "tasks").glob("*.js"),
        web / "static" / "study.css",
        *(web / "viewer").glob("*"),
    ]


def build_plugin() -> Path:
    """The plugin's browser bundle, built when missing or older than its sources."""
    stale = not BUNDLE.is_file() or max(p.stat().st_mtime for p in _sources()) > (
        BUNDLE.stat().st_mtime
    )
    if stale:
        node = shutil.which("node")
        if node is None:
            raise RuntimeError("building the jsPsych plugin needs Node.js and `npm ci`")
        subprocess.run([node, str(PLUGIN / "build.mjs")], cwd=REPO, check=True, capture_output=True)
    return BUNDLE


def readme_page() -> str:
    """The complete page of the plugin's README (its ```html block)."""
    text = (PLUGIN / "README.md").read_text()
    found = re.search(r"```html\n(.*?)```", text, re.S)
    if found is None:
        raise RuntimeError("the plugin's README has no ```html example page")
    return found.group(1)


def local_page(page: str, server: str) -> str:
    """``page`` with its CDN addresses on this site and its SERVER at ``server``."""
    for cdn in VENDOR:
        page = page.replace(cdn, f"/vendor/{cdn.rsplit('/', 2)[-2]}/")
    return re.sub(r'const SERVER = "[^"]*";', f"const SERVER = {json.dumps(server)};", page)


def one_trial_page(server: str, trials: list[dict[str, object]], setup: str = "") -> str:
    """A page of emogen trials only (wrong-use tests, the benchmark); ``window.done`` at the end,
    ``window.firstFacesAt``: performance.now() when the first faces were drawn; ``setup``: code
    run after jsPsych is made (e.g. jsPsych's Prolific recipe, ``jsPsych.data.addProperties``)."""
    timeline = json.dumps([{**t, "server": server} for t in trials])
    return f"""<!doctype html><html><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<script src="/vendor/jspsych@8.3.0/dist/index.browser.min.js"></script>
<script src="/vendor/jspsych-plugin-emogen/dist/index.browser.min.js"></script>
<link rel="stylesheet" href="/vendor/jspsych@8.3.0/css/jspsych.css">
<link rel="stylesheet" href="/vendor/jspsych-plugin-emogen/dist/emogen.css">
</head><body></body><script>
new MutationObserver((_, observer) => {{
  const ready = document.querySelector(".emogen-trial[data-emogen-ready='true']");
  if (ready && window.firstFacesAt === undefined) {{
    window.firstFacesAt = performance.now();
    observer.disconnect();
  }}
}}).observe(document, {{ subtree: true, attributes: true, childList: true }});
const jsPsych = initJsPsych({{ on_finish: () => (window.done = true) }});
{setup}
jsPsych.run({timeline}.map((t) => ({{ ...t, type: jsPsychEmogen }})));
</script></html>"""


class ExperimentSite:
    """The site on 127.0.0.1 (reached as http://localhost:PORT and, another origin, as
    http://127.0.0.1:PORT); ``add(name, html)`` puts a page there."""

    def __init__(self, root: Path) -> None:
        self.root = root
        vendor = root / "vendor"
        for cdn, source in VENDOR.items():
            name = cdn.rsplit("/", 2)[-2]
            for part in ("dist", "css"):
                if (source / part).is_dir():
                    shutil.copytree(source / part, vendor / name / part, dirs_exist_ok=True)
        handler = functools.partial(_QuietHandler, directory=str(root))
        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        self.port = self.httpd.server_address[1]
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self.thread.start()

    @property
    def origin(self) -> str:
        return f"http://localhost:{self.port}"

    @property
    def other_origin(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def add(self, name: str, html: str) -> str:
        (self.root / name).write_text(html)
        return f"{self.origin}/{name}"

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:
        pass
