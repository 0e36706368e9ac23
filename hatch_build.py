"""Build hook: every wheel carries the face viewer bundle (``npm run build``).

The bundle (``src/emogen/web/static/build/``) is built, not committed. A wheel built from a
clean checkout (``python -m build``, ``pip wheel .``) runs ``npm ci`` and ``npm run build`` here
when the bundle is missing; without npm the build stops with one message saying what to
install, instead of producing a wheel whose study server cannot show faces.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path
from typing import Any

from hatchling.builders.hooks.plugin.interface import BuildHookInterface

BUNDLE = Path("src/emogen/web/static/build/study-viewer.js")


def ensure_viewer(root: Path, npm: str | None = None) -> Path:
    """The viewer bundle under ``root``, built with npm when missing (RuntimeError if it cannot)."""
    bundle = root / BUNDLE
    if bundle.is_file():
        return bundle
    npm = npm or shutil.which("npm")
    if npm is None or not (root / "package.json").is_file():
        raise RuntimeError(
            f"the face viewer bundle {BUNDLE} is missing and cannot be built here "
            f"({'npm is not installed' if npm is None else 'no package.json'}): install Node.js "
            "18+ with npm, or run `npm ci && npm run build` in the source tree first"
        )
    if not (root / "node_modules").is_dir():
        subprocess.run([npm, "ci", "--no-audit", "--no-fund"], cwd=root, check=True)
    subprocess.run([npm, "run", "build"], cwd=root, check=True)
    if not bundle.is_file():
        raise RuntimeError(f"`npm run build` did not write {BUNDLE}")
    return bundle


class ViewerBuildHook(BuildHookInterface):  # type: ignore[misc]
    PLUGIN_NAME = "custom"

    def initialize(self, version: str, build_data: dict[str, Any]) -> None:
        if self.target_name == "wheel":
            ensure_viewer(Path(self.root))
