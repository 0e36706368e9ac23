"""The plugin as a lab installs it (#40): ``npm pack`` makes the tarball (its prepack builds
dist/), which holds the browser and ES module builds, the styles, TypeScript declarations and
the README — nothing else; unpacked into a fresh site's ``node_modules`` it runs an EmoGen trial
in Chromium from a ``<script>`` tag, bundled by esbuild from ``import EmogenPlugin from
"jspsych-plugin-emogen"``, and a TypeScript timeline type-checks against its declarations.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tarfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from benchmarks.bench_study import ServerProcess
from benchmarks.jspsych_site import NODE_MODULES, PLUGIN, ExperimentSite

from tests.web.test_jspsych_browser import READY, open_page, serve
from tests.web.test_study_browser import browser, viewer_bundle

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle)  # fixtures, requested by name

STUDY: dict[str, Any] = {
    "name": "packed",
    "identities": ["female-medium"],
    "seed": 4,
    "ga": {"generations": 1, "min_selections": 2, "max_selections": 3},
    "blocks": [{"task": "evolve"}],
}
TIMELINE = """[{ type: EmogenPlugin, server: SERVER, task: "evolve", patience_ms: 20000 }]"""


@pytest.fixture(scope="module")
def packed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``npm pack`` of the plugin, as its README says to make it."""
    npm = shutil.which("npm")
    if npm is None:
        pytest.fail("npm is needed to pack the plugin (Node.js)")
    out = tmp_path_factory.mktemp("pack")
    done = subprocess.run(
        [npm, "pack", "--pack-destination", str(out), "--json"],
        cwd=PLUGIN,
        check=True,
        capture_output=True,
        text=True,
    )
    (made,) = json.loads(done.stdout[done.stdout.index("[\n") :])  # after prepack's own lines
    return out / made["filename"]


def test_the_tarball_holds_the_builds_and_nothing_else(packed: Path) -> None:
    with tarfile.open(packed) as tar:
        names = sorted(tar.getnames())
        manifest = json.loads(tar.extractfile("package/package.json").read())  # type: ignore[union-attr]
    assert names == [
        f"package/{n}"
        for n in (
            "README.md",
            "dist/emogen.css",
            "dist/index.browser.min.js",
            "dist/index.d.ts",
            "dist/index.js",
            "package.json",
        )
    ]
    assert packed.name == f"jspsych-plugin-emogen-{manifest['version']}.tgz"
    assert manifest["types"] == "dist/index.d.ts"


@pytest.fixture(scope="module")
def lab(packed: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[ExperimentSite]:
    """A fresh site: jsPsych and the unpacked tarball in its node_modules."""
    site = ExperimentSite(tmp_path_factory.mktemp("lab"))
    modules = site.root / "node_modules"
    with tarfile.open(packed) as tar:
        tar.extractall(modules, filter="data")
    (modules / "package").rename(modules / "jspsych-plugin-emogen")
    shutil.copytree(NODE_MODULES / "jspsych", modules / "jspsych")
    yield site
    site.close()


def test_the_declarations_type_check_a_timeline(lab: ExperimentSite) -> None:
    source = lab.root / "timeline.ts"
    source.write_text(
        'import { initJsPsych } from "jspsych";\n'
        'import EmogenPlugin from "jspsych-plugin-emogen";\n'
        "const jsPsych = initJsPsych();\n"
        'const SERVER = "https://study.example.org";\n'
        f"jsPsych.run({TIMELINE});\n"
        "export const cite: string = EmogenPlugin.info.citations.apa;\n"
    )
    tsc = [str(NODE_MODULES / ".bin" / "tsc"), "--noEmit", "--strict", "--skipLibCheck"]
    tsc += ["--module", "es2022", "--moduleResolution", "bundler", "--lib", "es2022,dom"]
    done = subprocess.run([*tsc, str(source)], cwd=lab.root, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout
    source.write_text(source.read_text().replace("citations.apa", "citations.mla"))
    refused = subprocess.run([*tsc, str(source)], cwd=lab.root, capture_output=True, text=True)
    assert "Property 'mla' does not exist" in refused.stdout  # the declarations are read


def page(head: str, body: str) -> str:
    return f"""<!doctype html><html><head><meta charset="utf-8">
<link rel="stylesheet" href="/node_modules/jspsych/css/jspsych.css">
<link rel="stylesheet" href="/node_modules/jspsych-plugin-emogen/dist/emogen.css">
{head}</head><body></body>{body}</html>"""


@pytest.fixture(scope="module")
def server(
    tmp_path_factory: pytest.TempPathFactory,
    lab: ExperimentSite,
    ict_dir: Path,
    viewer_bundle: Path,
) -> Iterator[ServerProcess]:
    srv, _url = serve(STUDY, lab, tmp_path_factory.mktemp("server"), ict_dir)
    yield srv
    srv.stop()


def run_one_generation(browser: Any, url: str) -> None:
    p = open_page(browser, url, (1366, 768))
    p.wait_for_selector(READY.format("trial"), timeout=60_000)
    cells = p.locator("#grid > .cell .face")
    cells.nth(0).click()
    cells.nth(1).click()
    p.click("#next")
    p.wait_for_selector(READY.format("trial"), timeout=60_000)
    assert p.inner_text("#gen-progress") == "Round 2 of 2"
    p.context.close()


def test_the_unpacked_package_runs_a_trial_by_script_tag_and_by_bundler(
    browser: Any, lab: ExperimentSite, server: ServerProcess
) -> None:
    script = page(
        '<script src="/node_modules/jspsych/dist/index.browser.min.js"></script>\n'
        '<script src="/node_modules/jspsych-plugin-emogen/dist/index.browser.min.js"></script>',
        f"<script>const SERVER = {json.dumps(server.url)};\n"
        f"initJsPsych().run({TIMELINE.replace('EmogenPlugin', 'jsPsychEmogen')});</script>",
    )
    run_one_generation(browser, lab.add("script.html", script) + "?PROLIFIC_PID=script-1")

    main = lab.root / "main.js"
    main.write_text(
        'import { initJsPsych } from "jspsych";\n'
        'import EmogenPlugin from "jspsych-plugin-emogen";\n'
        f"const SERVER = {json.dumps(server.url)};\n"
        f"initJsPsych().run({TIMELINE});\n"
    )
    bundle = (  # the lab's bundler; jsPsych's own dependencies from the repository's modules
        "require('esbuild').buildSync({ entryPoints: ['main.js'], bundle: true, format: 'esm',"
        f" outfile: 'bundle.js', nodePaths: [{json.dumps(str(NODE_MODULES))}] }})"
    )
    subprocess.run(
        ["node", "-e", bundle],
        cwd=lab.root,
        check=True,
        env={**os.environ, "NODE_PATH": str(NODE_MODULES)},
    )
    bundled = page('<script type="module" src="/bundle.js"></script>', "")
    run_one_generation(browser, lab.add("bundled.html", bundled) + "?PROLIFIC_PID=bundle-1")
