"""Offscreen rendering: PNG stimuli, contact sheets and error heatmaps (moderngl, headless).

    from emogen.render import Renderer
    with Renderer(model, size=512) as r:
        images = r.render(weights)          # (n_faces, 512, 512, 3) uint8 sRGB

The camera, lights and materials live in ``look.json``, shared with the browser viewer.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "Renderer",
    "add_footer",
    "contact_sheet",
    "default_look",
    "render_faces",
    "render_heatmap",
    "save_png",
    "vertex_distances",
]

_WHERE = {
    "Renderer": "emogen.render.renderer",
    "render_faces": "emogen.render.renderer",
    "render_heatmap": "emogen.render.distance_map",
    "vertex_distances": "emogen.render.distance_map",
    "add_footer": "emogen.render.images",
    "contact_sheet": "emogen.render.images",
    "save_png": "emogen.render.images",
    "default_look": "emogen.render.look",
}


def __getattr__(name: str) -> Any:  # lazy: the CLI imports this package without numpy work
    if name in _WHERE:
        import importlib

        return getattr(importlib.import_module(_WHERE[name]), name)
    raise AttributeError(name)
