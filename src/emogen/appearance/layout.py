"""The skin's texture layout: which rest-mesh point every texel shows.

ICT-FaceKit lays its UVs out in tiles (UDIM style): the face in u ∈ [0, 1], head and neck in
u ∈ [1, 2]. The skin atlas covers both tiles side by side: an ``(H, 2H)`` image whose texel
``(row i, column j)`` is at glTF UV ``(2 (j + ½) / 2H, (i + ½) / H)`` — OBJ ``v = 1 − glTF v``.

Every skin triangle is rasterised into the atlas once (compiled with numba: a loop over each
triangle's texels), giving for each texel its triangle and barycentric coordinates; the
appearance is then painted from the texel's rest position in centimetres. Texels outside every
island are filled from the nearest island texel so that filtering never bleeds background in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from scipy import ndimage

from emogen.errors import ShapeError
from emogen.model.face import FaceModel

#: Regions painted by the skin atlas (the look's "skin" and "eye_socket" parts: the inner
#: lids carry the skin's tone too)
SKIN_REGIONS = ("face", "head_neck", "eye_socket_left", "eye_socket_right")
TILES = 2


@numba.njit(cache=True, nogil=True)
def _rasterise(uv: np.ndarray, height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Triangles (T, 3, 2) in texel units (x right, y down) → (H, W) triangle ids (−1: none)
    and (H, W, 3) barycentric weights of the texel centres covered (last triangle wins)."""
    tri = np.full((height, width), -1, dtype=np.int32)
    bary = np.zeros((height, width, 3), dtype=np.float32)
    for t in range(uv.shape[0]):
        x0, y0 = uv[t, 0, 0], uv[t, 0, 1]
        x1, y1 = uv[t, 1, 0], uv[t, 1, 1]
        x2, y2 = uv[t, 2, 0], uv[t, 2, 1]
        det = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2)
        if abs(det) < 1e-12:
            continue
        lo_x = max(int(np.floor(min(x0, x1, x2) - 0.5)), 0)
        hi_x = min(int(np.ceil(max(x0, x1, x2) - 0.5)), width - 1)
        lo_y = max(int(np.floor(min(y0, y1, y2) - 0.5)), 0)
        hi_y = min(int(np.ceil(max(y0, y1, y2) - 0.5)), height - 1)
        for i in range(lo_y, hi_y + 1):
            py = i + 0.5
            for j in range(lo_x, hi_x + 1):
                px = j + 0.5
                a = ((y1 - y2) * (px - x2) + (x2 - x1) * (py - y2)) / det
                b = ((y2 - y0) * (px - x2) + (x0 - x2) * (py - y2)) / det
                c = 1.0 - a - b
                if a >= -1e-6 and b >= -1e-6 and c >= -1e-6:
                    tri[i, j] = t
                    bary[i, j, 0] = a
                    bary[i, j, 1] = b
                    bary[i, j, 2] = c
    return tri, bary


@dataclass(frozen=True, eq=False)
class SkinLayout:
    """The atlas: ``height`` × ``2·height`` texels.

    triangles : (T, 3) int32 model vertex ids of the skin triangles
    texel_tri : (H, W) int32 triangle of each texel (−1 outside every island)
    bary : (H, W, 3) float32 barycentric weights (zero outside)
    nearest : (H, W) int64 flat index of the nearest covered texel (itself when covered)
    """

    height: int
    triangles: np.ndarray
    texel_tri: np.ndarray
    bary: np.ndarray
    nearest: np.ndarray

    @property
    def width(self) -> int:
        return TILES * self.height

    @property
    def covered(self) -> np.ndarray:
        return self.texel_tri >= 0

    def interpolate(self, values: np.ndarray) -> np.ndarray:
        """Per-vertex values (V, …) → per-texel (H, W, …), filled outside the islands."""
        v = np.asarray(values)
        tri = self.texel_tri.reshape(-1)[self.nearest.reshape(-1)]
        bary = self.bary.reshape(-1, 3)[self.nearest.reshape(-1)]
        corners = self.triangles[tri]  # (H·W, 3)
        out = np.einsum("nk,nk...->n...", bary, v[corners].astype(np.float32))
        return out.reshape(self.height, self.width, *v.shape[1:])


def skin_triangles(model: FaceModel) -> tuple[np.ndarray, np.ndarray]:
    """(T, 3) vertex ids and (T, 3) UV ids of the skin regions' triangles (quads split a-b-c,
    a-c-d, as everywhere in EmoGen)."""
    missing = [r for r in SKIN_REGIONS if r not in model.regions]  # ICT's layout
    if missing or len(model.uvs) == 0:
        raise ShapeError(
            f"the skin atlas needs the regions {list(SKIN_REGIONS)} and UVs; model "
            f"'{model.name}' lacks {missing or 'UVs'}"
        )
    polys = np.concatenate(
        [np.arange(model.regions[r].p_start, model.regions[r].p_stop) for r in SKIN_REGIONS]
    )
    p, puv = model.polygons[polys], model.polygon_uvs[polys]
    quad = p[:, 3] >= 0
    verts = np.concatenate([p[:, [0, 1, 2]], p[quad][:, [0, 2, 3]]])
    uvs = np.concatenate([puv[:, [0, 1, 2]], puv[quad][:, [0, 2, 3]]])
    ok = (uvs >= 0).all(1)
    return verts[ok].astype(np.int32), uvs[ok].astype(np.int64)


def skin_layout(model: FaceModel, height: int) -> SkinLayout:
    """Rasterise the skin triangles into a ``height`` × ``2·height`` atlas."""
    if not 64 <= height <= 8192:
        raise ShapeError(f"texture height must be in [64, 8192]; got {height}")
    width = TILES * height
    verts, uv_ids = skin_triangles(model)
    uv = model.uvs[uv_ids].astype(np.float64)  # (T, 3, 2) OBJ convention, u in [0, 2]
    texel = np.empty_like(uv)
    texel[..., 0] = uv[..., 0] / TILES * width
    texel[..., 1] = (1.0 - uv[..., 1]) * height
    tri, bary = _rasterise(texel, height, width)
    covered = tri >= 0
    _, idx = ndimage.distance_transform_edt(~covered, return_indices=True)
    nearest = np.ravel_multi_index((idx[0], idx[1]), covered.shape)
    return SkinLayout(height, verts, tri, bary, nearest)
