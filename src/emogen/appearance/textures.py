"""The skin textures of an identity: generated once, cached as WebP, shared by both renderers.

Two images travel with every textured face:

* the **skin atlas** (``height`` × ``2·height`` sRGB, lossy WebP) painted by
  :mod:`emogen.appearance.paint` for one (model, identity shape, appearance);
* the **detail tile** (``DETAIL_PX``² lossless WebP, the same for every face): a tileable
  micro-relief (R: height, G: roughness) repeated over the skin, so skin is not plastic.

WebP, not KTX2/Basis: Chromium and Pillow both decode it natively (no transcoder to ship, no
encoder binary outside the package registries), it is 5-10× smaller than PNG for the atlas,
and the offscreen renderer decodes the *same bytes* the browser does, so both sample identical
texels. The cache key covers the model hash, the identity coefficients, every appearance
parameter, the generator version and the sizes; a corrupt or unreadable cache entry is rebuilt.
"""

from __future__ import annotations

import hashlib
import io
import logging
import os
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np
from PIL import Image

from emogen.appearance.features import FaceFeatures, face_features
from emogen.appearance.layout import SkinLayout, skin_layout
from emogen.appearance.paint import Texels, linear_to_srgb, paint_albedo
from emogen.appearance.params import GENERATOR_VERSION, Appearance
from emogen.model.face import FaceModel

log = logging.getLogger(__name__)

DEFAULT_HEIGHT = 1024
DETAIL_PX = 256
WEBP_QUALITY = 90


@dataclass(frozen=True, eq=False)
class SkinTextures:
    """The decoded images (what both renderers sample) and their WebP bytes."""

    appearance: Appearance
    albedo: np.ndarray  # (H, 2H, 3) uint8 sRGB, row 0 at glTF v = 0
    detail: np.ndarray  # (D, D, 3) uint8: R height, G roughness, B 128
    albedo_webp: bytes
    detail_webp: bytes
    key: str


def vertex_cavity(vertices: np.ndarray, triangles: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(V,) concavity in [0, 1]: how far the neighbours' mean lies along the unit vertex
    normal, relative to the squared edge length (a discrete mean curvature, cm⁻¹)."""
    v = np.asarray(vertices, dtype=np.float64)
    n_v = len(v)
    pairs = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    pairs = np.sort(pairs, axis=1).astype(np.int64)
    key = np.unique(pairs[:, 0] * n_v + pairs[:, 1])
    a, b = key // n_v, key % n_v
    edges = np.stack([a, b], 1)
    deg = np.bincount(edges.ravel(), minlength=n_v).astype(np.float64)
    acc = np.stack(
        [np.bincount(a, v[b, k], n_v) + np.bincount(b, v[a, k], n_v) for k in range(3)], 1
    )
    d2 = ((v[a] - v[b]) ** 2).sum(1)
    length2 = np.bincount(a, d2, n_v) + np.bincount(b, d2, n_v)
    has = deg > 0
    lap = np.zeros_like(v)
    lap[has] = acc[has] / deg[has, None] - v[has]
    mean_len2 = np.where(has, length2 / np.maximum(deg, 1), 1.0)
    curvature = 2 * (lap * normals).sum(1) / np.maximum(mean_len2, 1e-9)
    return np.clip((curvature - 0.25) / 1.2, 0.0, 1.0)


def texels(model: FaceModel, layout: SkinLayout, features: FaceFeatures) -> Texels:
    """The painters' inputs at the covered texels of ``layout``."""
    from emogen.model.geometry import vertex_normals

    n = model.neutral.astype(np.float64)
    index = np.flatnonzero(layout.covered)
    corners = layout.triangles[layout.texel_tri.reshape(-1)[index]]  # (n, 3)
    bary = layout.bary.reshape(-1, 3)[index].astype(np.float64)

    def at(values: np.ndarray) -> np.ndarray:
        return np.einsum("nk,nk...->n...", bary, values[corners])

    vertex_n = vertex_normals(n, layout.triangles)
    normals = at(vertex_n)
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    pos = at(n)
    face = model.regions["face"]
    return Texels(
        pos=pos,
        normal=normals,
        cyl=features.cylindrical(pos),
        theta=features.theta_deg(pos),
        face=(corners[:, 0] >= face.v_start) & (corners[:, 0] < face.v_stop),
        lids=np.isin(
            corners[:, 0],
            np.concatenate(
                [model.regions[r].vertex_indices() for r in ("eye_socket_left", "eye_socket_right")]
            ),
        ),
        cavity=at(vertex_cavity(n, layout.triangles, vertex_n)),
        shape=(layout.height, layout.width),
        index=index,
        corners=corners,
        bary=bary,
        vertex_pos=n,
        vertex_normal=vertex_n,
    )


def texel_size_cm(t: Texels) -> float:
    """Median distance (cm) between horizontally adjacent covered texels of the face tile."""
    _row, col = np.divmod(t.index, t.shape[1])
    nxt = np.searchsorted(t.index, t.index + 1)
    ok = (nxt < len(t.index)) & (col < t.shape[0] - 1)
    ok[ok] &= t.index[nxt[ok]] == t.index[ok] + 1
    d = np.linalg.norm(t.pos[nxt[ok]] - t.pos[ok], axis=1)
    return float(np.median(d)) if len(d) else 0.05


def paint_skin(
    model: FaceModel, appearance: Appearance, *, irradiance: float, height: int = DEFAULT_HEIGHT
) -> np.ndarray:
    """The skin atlas (H, 2H, 3) uint8 sRGB of ``model``'s identity with ``appearance``."""
    layout = skin_layout(model, height)
    features = face_features(model)
    t = texels(model, layout, features)
    lin = paint_albedo(t, features, appearance, irradiance, texel_size_cm(t))
    # texels outside the islands take their nearest island texel's colour (no filter bleeding)
    rank = np.zeros(layout.height * layout.width, dtype=np.int64)
    rank[t.index] = np.arange(len(t.index))
    full = lin[rank[layout.nearest.reshape(-1)]]
    srgb = linear_to_srgb(full).reshape(layout.height, layout.width, 3)
    return np.round(srgb * 255).astype(np.uint8)


def detail_tile(size: int = DETAIL_PX, seed: int = 20261122) -> np.ndarray:
    """A tileable micro-relief (size, size, 3) uint8: R height (pores are dips), G roughness."""
    rng = np.random.default_rng(seed)
    f = np.fft.fftfreq(size)
    k = np.hypot(*np.meshgrid(f, f, indexing="ij"))

    def band(lo: float, hi: float) -> np.ndarray:
        spec = np.fft.fft2(rng.standard_normal((size, size)))
        x = np.real(np.fft.ifft2(spec * ((k > lo) & (k < hi))))
        return x / max(float(x.std()), 1e-12)

    fine, mid = band(0.12, 0.45), band(0.03, 0.12)
    pores = np.clip(-band(0.15, 0.35) - 1.6, 0, None)
    height = 0.35 * fine + 0.5 * mid - 1.2 * pores
    rough = 0.6 * mid + 0.4 * fine
    out = np.empty((size, size, 3), dtype=np.uint8)
    out[..., 0] = np.clip(128 + 30 * height, 0, 255)
    out[..., 1] = np.clip(128 + 40 * rough, 0, 255)
    out[..., 2] = 128
    return out


def _encode(image: np.ndarray, *, lossless: bool) -> bytes:
    buf = io.BytesIO()
    # lossless: quality is encoding effort (50: 73 kB in 20 ms; 100 saves 1 % for 2.6 s)
    Image.fromarray(image, "RGB").save(
        buf,
        "WEBP",
        lossless=lossless,
        quality=50 if lossless else WEBP_QUALITY,
        method=6 if not lossless else 2,
    )
    return buf.getvalue()


def decode_webp(data: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(data)) as im:
        return np.asarray(im.convert("RGB"))


@cache
def _painter_source_hash() -> str:
    """Hash of the painting code itself: any change to it invalidates cached textures."""
    h = hashlib.sha256()
    for mod in ("features", "layout", "paint", "params", "textures"):
        h.update(resources.files("emogen.appearance").joinpath(f"{mod}.py").read_bytes())
    return h.hexdigest()


def textures_key(model: FaceModel, appearance: Appearance, height: int, irradiance: float) -> str:
    h = hashlib.sha256()
    h.update(_painter_source_hash().encode())
    h.update(f"{model.model_hash}\n{GENERATOR_VERSION}\n{height}\n{DETAIL_PX}\n".encode())
    h.update(f"{irradiance:.6f}\n".encode())
    h.update(np.ascontiguousarray(model.identity, dtype=np.float64).tobytes())
    h.update(appearance.key().encode())
    return h.hexdigest()[:32]


def _cache_dir() -> Path:
    from emogen.model.io.cache import cache_root

    return cache_root() / "appearance"


def _write_atomic(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _cached(path: Path, make: Callable[[], bytes]) -> bytes:
    try:
        stored = path.read_bytes()
        decode_webp(stored)  # a truncated or corrupt file is rebuilt
        return stored
    except (OSError, ValueError, Image.UnidentifiedImageError) as exc:
        if not isinstance(exc, FileNotFoundError):
            log.warning("rebuilding unreadable texture cache %s: %s", path, exc)
    data = make()
    try:
        _write_atomic(path, data)
    except OSError as exc:
        log.warning("could not cache textures under %s: %s", path.parent, exc)
    return data


def skin_textures(
    model: FaceModel,
    appearance: Appearance,
    *,
    irradiance: float,
    height: int = DEFAULT_HEIGHT,
) -> SkinTextures:
    """The textures of ``model``'s identity with ``appearance`` (cached on disk)."""
    key = textures_key(model, appearance, height, irradiance)
    folder = _cache_dir()
    albedo_webp = _cached(
        folder / f"skin-{key}.webp",
        lambda: _encode(
            paint_skin(model, appearance, irradiance=irradiance, height=height), lossless=False
        ),
    )
    detail_webp = _cached(
        folder / f"detail-v{GENERATOR_VERSION}-{DETAIL_PX}.webp",
        lambda: _encode(detail_tile(), lossless=True),
    )
    return SkinTextures(
        appearance=appearance,
        albedo=decode_webp(albedo_webp),
        detail=decode_webp(detail_webp),
        albedo_webp=albedo_webp,
        detail_webp=detail_webp,
        key=key,
    )
