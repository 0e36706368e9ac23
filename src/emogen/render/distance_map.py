"""Error heatmaps: per-vertex distance between two faces as colour on the face, with a legend in cm.

Like the paper's Fig. 9: the face is drawn with the same camera and light as any stimulus, its
skin coloured by how far each vertex lies from the reference face (default colour map ``viridis``, perceptually uniform and colour-blind-safe,
blue = 0, red = ``vmax``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from emogen.errors import ConfigError, ShapeError
from emogen.render.images import add_footer, colourbar
from emogen.render.renderer import Renderer
from emogen.render.scene import srgb_to_linear

# Parts coloured by distance; eyes and lashes keep their look so the face stays readable.
HEAT_PARTS = ("skin", "mouth_socket", "eye_socket", "gums_tongue", "teeth")


def vertex_distances(faces: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Euclidean distance per vertex: faces (B, V, 3) or (V, 3) vs reference of the same shape
    or (V, 3) → (B, V) or (V,) float64, in the model's unit (cm)."""
    a = np.asarray(faces, dtype=np.float64)
    b = np.asarray(reference, dtype=np.float64)
    if a.shape[-2:] != b.shape[-2:] or a.shape[-1] != 3:
        raise ShapeError(f"faces {a.shape} and reference {b.shape} must both be (…, V, 3)")
    return np.asarray(np.linalg.norm(a - b, axis=-1))


#: Perceptually uniform maps for magnitudes, and the rainbow maps refused for them.
PERCEPTUAL_MAPS = ("viridis", "cividis", "magma", "inferno", "plasma")
RAINBOW_MAPS = ("jet", "turbo", "rainbow", "gist_rainbow", "hsv", "nipy_spectral", "gist_ncar")


def colour_lut(cmap: str = "viridis") -> np.ndarray:
    """(256, 3) sRGB in [0, 1] of a matplotlib colour map. Distances are magnitudes: maps
    that are not perceptually ordered (jet, turbo, rainbow, …) mislead and fail colour-blind
    readers, and are refused."""
    import matplotlib

    if cmap.lower().removesuffix("_r") in RAINBOW_MAPS:
        raise ConfigError(
            f"colour map {cmap!r} is not perceptually uniform (it invents edges and fails "
            f"colour-blind readers); use one of {', '.join(PERCEPTUAL_MAPS)}"
        )
    try:
        cm = matplotlib.colormaps[cmap]
    except KeyError:
        raise ConfigError(
            f"unknown colour map {cmap!r}; try {', '.join(PERCEPTUAL_MAPS)}"
        ) from None
    return np.asarray(cm(np.linspace(0.0, 1.0, 256))[:, :3])


def nice_ceiling(x: float) -> float:
    """Round up to 1, 1.5, 2, 2.5, 3, 4, 5, 6 or 8 × 10^k (legend ranges like 0.5 cm, 3 cm)."""
    if x <= 0:
        return 1.0
    k = np.floor(np.log10(x))
    for m in (1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0):
        if m * 10**k >= x * (1 - 1e-9):
            return float(m * 10**k)
    return float(10 ** (k + 1))  # pragma: no cover


@dataclass(frozen=True)
class Heatmap:
    image: np.ndarray  # (H, W, 3) uint8: face and legend
    distances: np.ndarray  # (V,) cm
    vmax: float  # legend's top, cm
    max_distance: float  # largest distance over the coloured parts, cm


def render_heatmap(
    renderer: Renderer,
    face: np.ndarray,
    reference: np.ndarray,
    *,
    vmax: float | None = None,
    cmap: str = "viridis",
    footer: str | None = None,
) -> Heatmap:
    """Draw ``face (V, 3)`` coloured by its distance to ``reference (V, 3)``, with a legend.

    vmax : top of the colour scale in cm (default: the largest distance rounded up to a nice
    number); footer None: the ICT-FaceKit notice, "" for none.
    """
    look, mesh = renderer.look, renderer.mesh
    dist = vertex_distances(face, reference)
    if dist.ndim != 1:
        raise ShapeError(f"face must be one mesh (V, 3); got {np.shape(face)}")
    names = [p.name for p in look.parts]
    coloured = np.isin(mesh.part.astype(int), [names.index(n) for n in HEAT_PARTS if n in names])
    largest = float(dist[coloured].max(initial=0.0))
    top = nice_ceiling(largest) if vmax is None else float(vmax)
    if not top > 0:
        raise ConfigError(f"vmax must be positive (cm); got {vmax}")
    lut = colour_lut(cmap)
    index = np.clip(np.rint(dist / top * 255), 0, 255).astype(int)
    albedo = mesh.albedo.copy()
    albedo[coloured] = srgb_to_linear(lut[index[coloured]]).astype(np.float32)
    image = renderer.render_vertices(np.asarray(face, dtype=np.float32)[None], albedo=albedo)[0]
    legend = colourbar(lut, top, height=image.shape[0], unit="cm", background=look.background_srgb)
    combined = np.concatenate([image, legend], axis=1)
    if footer != "":
        combined = add_footer(combined, footer, background=look.background_srgb)
    return Heatmap(combined, dist, top, largest)
