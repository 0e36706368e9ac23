"""Fixtures of the face-viewer browser tests (imported by test_viewer.py): the built viewer
served from a temporary folder, and Debian's Chromium through Playwright.

The viewer is built by `npm run build` (the setup command); a missing or stale build is rebuilt
here. The server is a plain http.server on 127.0.0.1 (port 0) serving the built files, the
model GLB (`face.glb`: the default identity, ``IDENTITY``, with its skin textures and fitted
camera, as the study server's ``ModelGLBs`` writes it) and, for the WebGL-less fallback,
`render.png?size=&weights=` rendered offscreen by emogen.render of the same identity — as the
study server will.
"""

from __future__ import annotations

import http.server
import os
import shutil
import subprocess
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlparse

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
VIEWER_SRC = REPO / "src" / "emogen" / "web" / "viewer"
BUILD = REPO / "src" / "emogen" / "web" / "static" / "build"
SHARED = [
    REPO / "src" / "emogen" / "render" / "look.json",
    REPO / "src" / "emogen" / "render" / "shaders" / "shade.glsl",
]
#: The identity the site serves (a preset of emogen.appearance.identities).
IDENTITY = "generic"
CHROMIUM = "/usr/bin/chromium"


def screenshot_folder(name: str) -> Path:
    """Where a browser test's screenshots go: docs/images with ``EMOGEN_UPDATE_SCREENSHOTS=1``
    (the pictures the docs show), else /tmp/emogen-<name>-screenshots."""
    if os.environ.get("EMOGEN_UPDATE_SCREENSHOTS") == "1":
        return REPO / "docs" / "images"
    return Path(f"/tmp/emogen-{name}-screenshots")


CHROMIUM_ARGS = [
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


def _stale() -> bool:
    out = BUILD / "viewer.js"
    if not out.is_file() or not (BUILD / "index.html").is_file():
        return True
    sources = [*VIEWER_SRC.iterdir(), *SHARED, REPO / "package-lock.json"]
    return max(p.stat().st_mtime for p in sources if p.is_file()) > out.stat().st_mtime


@pytest.fixture(scope="session")
def viewer_build() -> Path:
    if _stale():
        npm = shutil.which("npm")
        if npm is None:
            pytest.fail("the viewer is not built and npm is missing: run `npm ci && npm run build`")
        proc = subprocess.run([npm, "run", "build"], cwd=REPO, capture_output=True, text=True)
        if proc.returncode != 0:
            pytest.fail(
                f"npm run build failed (run `npm ci` first?):\n{proc.stdout}\n{proc.stderr}"
            )
    return BUILD


def identity_model(ict_model: Any, name: str = IDENTITY) -> tuple[Any, Any]:
    """(model with the identity's shape, its appearance)."""
    from emogen.appearance.identities import resolve_identity

    identity = resolve_identity(name)
    return ict_model.with_identity(identity.shape), identity.appearance


def offscreen_renderer(
    ict_model: Any,
    size: int,
    name: str = IDENTITY,
    supersample: int | None = None,
    framing: str | None = None,
) -> Any:
    """The offscreen renderer of what the site's GLB shows: same identity, appearance, camera
    (``oval``: the same camera, through the oval)."""
    from emogen.render.renderer import Renderer

    model, appearance = identity_model(ict_model, name)
    return Renderer(
        model, size=size, appearance=appearance, supersample=supersample, framing=framing
    )


def export_site_glb(ict_model: Any, path: Path, name: str = IDENTITY) -> Any:
    """The identity's textured GLB with its fitted camera (as emogen.web.assets.ModelGLBs)."""
    from emogen.appearance.textures import skin_textures
    from emogen.render.look import default_look, fitted_look
    from emogen.render.model_glb import export_model_glb

    model, appearance = identity_model(ict_model, name)
    look = default_look()
    textures = skin_textures(model, appearance, irradiance=look.front_irradiance())
    camera = fitted_look(look, model, appearance).camera
    return export_model_glb(model, path, textures=textures, camera=camera)


class _Handler(http.server.SimpleHTTPRequestHandler):
    renderers: dict[int, Any]
    model: Any

    def log_message(self, format: str, *args: Any) -> None:
        pass

    def do_GET(self) -> None:
        url = urlparse(self.path)
        if url.path != "/render.png":
            super().do_GET()
            return
        from emogen.render.images import png_bytes

        q = parse_qs(url.query)
        size = int(q.get("size", ["256"])[0])
        text = q.get("weights", [""])[0]
        w = np.zeros((1, self.model.n_shapes))
        if text:
            values = [float(x) for x in text.split(",")]
            w[0, : len(values)] = values
        if size not in self.renderers:  # made in the server's own thread: one GL context
            self.renderers[size] = offscreen_renderer(self.model, size)
        body = png_bytes(self.renderers[size].render(w)[0])
        self.send_response(200)
        self.send_header("Content-Type", "image/png")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)


@dataclass
class Site:
    url: str
    folder: Path
    glb_bytes: int


@pytest.fixture(scope="session")
def viewer_site(
    viewer_build: Path, ict_model, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[Site]:  # type: ignore[no-untyped-def]
    folder = tmp_path_factory.mktemp("site")
    for f in viewer_build.iterdir():
        if f.is_file():
            shutil.copy(f, folder / f.name)
    report = export_site_glb(ict_model, folder / "face.glb")
    handler = type("Handler", (_Handler,), {"renderers": {}, "model": ict_model})

    def make(*args: Any) -> http.server.SimpleHTTPRequestHandler:
        return handler(*args, directory=str(folder))

    server = http.server.HTTPServer(("127.0.0.1", 0), make)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield Site(f"http://127.0.0.1:{server.server_address[1]}", folder, report.raw_bytes)
    finally:
        server.shutdown()
        server.server_close()


def launch(playwright: Any, *extra: str) -> Any:
    if not Path(CHROMIUM).exists():
        pytest.fail(f"browser tests need Debian's Chromium at {CHROMIUM}: apt-get install chromium")
    # Playwright starts Chromium with a fresh temporary --user-data-dir of its own.
    return playwright.chromium.launch(
        executable_path=CHROMIUM, headless=True, args=[*CHROMIUM_ARGS, *extra]
    )


@pytest.fixture(scope="module")  # as playwright_api (tests/web/conftest.py)
def chromium(playwright_api: Any) -> Iterator[Any]:
    b = launch(playwright_api)
    try:
        yield b
    finally:
        b.close()
