"""Long hair as a layer over the ``face`` framing: one RGBA image per identity and size.

ICT-FaceKit has no hair and a painted crop does not show from the front (docs/appearance.md), so
``hair = "long"`` frames the face with a curtain of hair parted in the middle: painted here in
image space from the identity's landmarks as the fitted ``face`` camera sees them, and laid over
every rendered face of the identity — offscreen by :func:`apply_layer`, in the browser by the
same RGBA image over each tile. The layer is fixed per identity (the hair does not move with the
expression), so it is built to leave everything an expression moves visible: its inner edge stays
outside the brows' tails, the eyes' outer corners (crow's feet) and the jaw's outline, above the
brows by more than a full brow raise, and beside the chin's full drop (tested with ``jawOpen``
and ``browInnerUp``/``browOuterUp`` at weight 1, tests/appearance/test_long_hair.py).

The painting (straight alpha, sRGB): a mask from two outlines (inner: round the face; outer: the
hair's volume), strands as iso-lines of the distance from the face (hair falls along the face's
edge), clumps and a sheen band across them, a wispy inner edge, and a soft shadow cast on the skin
just inside it. Painted at twice the size and averaged down (anti-aliasing).
"""

from __future__ import annotations

import io
from typing import TYPE_CHECKING, Protocol

import numpy as np
from scipy import ndimage

from emogen.appearance.paint import linear_to_srgb, smoothstep, srgb_to_linear
from emogen.appearance.params import Appearance, hex_to_srgb

if TYPE_CHECKING:
    from emogen.model.face import FaceModel


class Camera(Protocol):
    """What the layer needs of a camera (:class:`emogen.render.look.Camera`): pixel positions
    (n, 2), x right and y down, of points (n, 3) in cm in a ``size``² image."""

    def project(self, points: np.ndarray, size: int) -> np.ndarray: ...


#: The layer's side in pixels, as the GLB carries it (a 512² tile at device pixel ratio 2).
LAYER_PX = 1024
#: Painted at this many times the layer's size, then averaged down (1: the edges are ramps
#: over a few pixels already).
OVERSAMPLE = 1
#: The darkest the shadow on the skin along the hair's inner edge gets (alpha of black).
SHADOW_ALPHA = 0.35


def _side(lm: np.ndarray, side: int, cx: float, half: float, height: float) -> np.ndarray:
    """Inner outline of one side's curtain (n, 2), pixels, from the parting down past the image's
    bottom: ``side`` −1 the image's left (landmarks 0–8), +1 its right (16–8)."""
    j = (lambda k: lm[k]) if side < 0 else (lambda k: lm[16 - k])
    b = (lambda k: lm[17 + k]) if side < 0 else (lambda k: lm[26 - k])
    out = np.array([side, 0.0])  # outward, as a unit x step
    brow_top = min(b(0)[1], b(2)[1])
    forehead = brow_top - 0.55 * (brow_top - 0.0)  # well above a full brow raise
    pts = [
        (cx + 0.06 * half * side, -0.05 * height),
        (cx + 0.28 * half * side, 0.025 * height),
        (b(2)[0] + out[0] * 0.02 * half, forehead),
        (b(0)[0] + out[0] * 0.16 * half, brow_top - 0.10 * half),
        (j(0)[0] + out[0] * 0.02 * half, j(0)[1]),
        (j(2)[0] + out[0] * 0.05 * half, j(2)[1]),
        (j(4)[0] + out[0] * 0.08 * half, j(4)[1]),
        # beside the jaw's side, which a jaw drop moves down and slightly in, then in to the
        # neck's side only under the fully dropped chin
        (j(5)[0] + out[0] * 0.10 * half, j(5)[1]),
        (j(5)[0] + out[0] * 0.08 * half, j(5)[1] + 0.20 * half),
        (j(6)[0] + out[0] * 0.02 * half, j(8)[1] + 0.50 * half),
        (j(6)[0] + out[0] * 0.02 * half, 1.10 * height),
    ]
    return _smooth(np.asarray(pts, dtype=np.float64))


def _outer(lm: np.ndarray, side: int, half: float, height: float) -> np.ndarray:
    """Outer outline of one side's curtain (n, 2), pixels: the hair's volume beside the head."""
    j0 = lm[0] if side < 0 else lm[16]
    j4 = lm[4] if side < 0 else lm[12]
    out = side
    pts = [
        (j0[0] + out * 0.05 * half, -0.05 * height),
        (j0[0] + out * 0.34 * half, 0.12 * height),
        (j0[0] + out * 0.42 * half, j0[1]),
        (j4[0] + out * 0.58 * half, j4[1]),
        (j4[0] + out * 0.62 * half, 0.9 * height),
        (j4[0] + out * 0.58 * half, 1.10 * height),
    ]
    return _smooth(np.asarray(pts, dtype=np.float64))


def _smooth(points: np.ndarray, per_segment: int = 24) -> np.ndarray:
    """A Catmull-Rom curve through ``points`` (n, 2), sampled ``per_segment`` times a segment."""
    p = np.vstack([points[0], points, points[-1]])
    t = np.linspace(0.0, 1.0, per_segment, endpoint=False)[:, None]
    curve = []
    for i in range(1, len(p) - 2):
        p0, p1, p2, p3 = p[i - 1], p[i], p[i + 1], p[i + 2]
        curve.append(
            0.5
            * (
                2 * p1
                + (p2 - p0) * t
                + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t**2
                + (3 * p1 - p0 - 3 * p2 + p3) * t**3
            )
        )
    curve.append(points[-1:])
    return np.vstack(curve)


def _inside(polygon: np.ndarray, n: int) -> np.ndarray:
    """(n, n) bool: pixels whose centre lies inside ``polygon`` (pixels)."""
    from PIL import Image, ImageDraw

    im = Image.new("1", (n, n), 0)
    ImageDraw.Draw(im).polygon([(float(x) - 0.5, float(y) - 0.5) for x, y in polygon], fill=1)
    return np.asarray(im, dtype=bool)


def _strand_profile(rng: np.random.Generator, n: int) -> np.ndarray:
    """Brightness across the strands, one value per strand-width step: fine strands over clumps."""
    fine = rng.normal(0.0, 1.0, n)
    clumps = ndimage.gaussian_filter1d(rng.normal(0.0, 1.0, n), 6.0, mode="wrap")
    clumps /= max(float(np.std(clumps)), 1e-9)
    return 0.16 * fine + 0.22 * clumps


def long_hair_layer(
    landmarks_px: np.ndarray, size: int, hair_colour: str, seed: int = 0
) -> np.ndarray:
    """(size, size, 4) uint8, straight-alpha sRGB: the curtain of hair and its shadow on the skin
    for a face whose 68 landmarks lie at ``landmarks_px`` (pixels, x right, y down, in a
    ``size``² image of the neutral under the ``face`` framing)."""
    lm = np.asarray(landmarks_px, dtype=np.float64)
    if lm.shape != (68, 2) or not np.all(np.isfinite(lm)):
        raise ValueError(f"landmarks_px must be 68 finite (x, y) points; got shape {lm.shape}")
    if size < 16:
        raise ValueError(f"the layer's size must be at least 16 pixels; got {size}")
    n = size * OVERSAMPLE
    lm = lm * OVERSAMPLE
    cx = float(lm[27, 0])
    half = float(lm[16, 0] - lm[0, 0]) / 2
    if half <= 0:
        raise ValueError("landmarks_px: the face's right edge (16) is not right of its left (0)")
    left, right = _side(lm, -1, cx, half, n), _side(lm, 1, cx, half, n)
    face = _inside(np.vstack([left, right[::-1]]), n)
    volume = _inside(np.vstack([_outer(lm, -1, half, n), _outer(lm, 1, half, n)[::-1]]), n)
    hair = volume & ~face
    # distance (pixels of the painting) from the face into the hair, and from the hair into the face
    d_in = ndimage.distance_transform_edt(~face)
    d_out = ndimage.distance_transform_edt(face)
    rng = np.random.default_rng(seed)
    unit = n / 512  # painting pixels per pixel of a 512² image
    warp = ndimage.gaussian_filter(rng.normal(0.0, 1.0, (n // 8 + 1, n // 8 + 1)), 3.0)
    warp = ndimage.zoom(warp / max(float(np.std(warp)), 1e-9), 8, order=1)[:n, :n]
    q = d_in + 2.5 * unit * warp  # strands follow the face's edge, gently waving
    profile = _strand_profile(rng, 4096)
    step = 1.1 * unit  # a strand about a pixel wide at 512²
    strands = np.interp(q / step, np.arange(len(profile)), profile, period=len(profile))
    yy = (np.arange(n)[:, None] + 0.5) / n
    sheen = np.exp(-(((yy - 0.22) / 0.07) ** 2)) * np.clip(1 + 2.5 * strands, 0, None)
    depth = smoothstep(0.0, 14 * unit, d_in) * 0.35 + 0.65  # darker where it meets the face
    rim = 1 - 0.35 * smoothstep(0.0, 1.0, ndimage.distance_transform_edt(volume) / (24 * unit))
    shade = np.clip((1 + strands) * depth * (2 - rim) / 1.35, 0.2, 2.0) + 0.55 * sheen
    colour = srgb_to_linear(np.array(hex_to_srgb(hair_colour, "hair_colour")))
    rgb = linear_to_srgb(colour[None, None, :] * shade[..., None] + 0.004 * sheen[..., None])
    wisps = 3.0 * unit * (strands / 0.3)
    a_hair = hair * smoothstep(-1.5 * unit, 2.5 * unit, d_in - 1.5 * unit + wisps)
    a_edge = smoothstep(0.0, 1.5 * unit, ndimage.distance_transform_edt(volume))
    a_hair = a_hair * np.where(volume, a_edge, 0.0)
    a_shadow = SHADOW_ALPHA * np.exp(-d_out / (5.0 * unit)) * face
    alpha = a_hair + a_shadow * (1 - a_hair)
    premult = rgb * a_hair[..., None]  # the shadow is black
    # average OVERSAMPLE² samples per pixel (premultiplied), then back to straight alpha
    k = OVERSAMPLE
    alpha = alpha.reshape(size, k, size, k).mean(axis=(1, 3))
    premult = premult.reshape(size, k, size, k, 3).mean(axis=(1, 3))
    straight = premult / np.maximum(alpha, 1e-9)[..., None]
    out = np.concatenate([straight, alpha[..., None]], axis=-1)
    return np.round(np.clip(out, 0.0, 1.0) * 255).astype(np.uint8)


def identity_layer(model: FaceModel, appearance: Appearance, camera: Camera) -> np.ndarray:
    """The layer of ``model``'s identity with ``appearance`` as ``camera`` (its fitted ``face``
    camera) sees its neutral: (LAYER_PX, LAYER_PX, 4) uint8."""
    from emogen.appearance.features import face_features

    points = camera.project(face_features(model).landmarks, LAYER_PX)
    return long_hair_layer(points, LAYER_PX, appearance.hair_colour, appearance.seed)


def layer_webp(layer: np.ndarray) -> bytes:
    """The layer as the bytes both renderers decode: WebP, the colour lossy (quality 90) and the
    alpha lossless, as the skin atlas (0.1–0.2 MB where PNG takes ~1.5 MB)."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(layer, "RGBA").save(buf, "WEBP", quality=90, alpha_quality=100, method=4)
    return buf.getvalue()


def decode_layer(data: bytes) -> np.ndarray:
    """(h, w, 4) uint8 of a layer's WebP bytes."""
    from PIL import Image

    with Image.open(io.BytesIO(data)) as im:
        return np.asarray(im.convert("RGBA"))


def resample_layer(layer: np.ndarray, size: int) -> np.ndarray:
    """The layer at ``size``² pixels: the mean of the pixels each covers, premultiplied (a box
    filter; the browser shows the LAYER_PX layer 1:1 on a 512² tile at device pixel ratio 2)."""
    if layer.shape[0] == size:
        return layer
    from PIL import Image

    a = layer[..., 3].astype(np.float32) / 255
    chans = [layer[..., c].astype(np.float32) * a for c in range(3)] + [a]
    small = [
        np.asarray(Image.fromarray(c, "F").resize((size, size), Image.Resampling.BOX))
        for c in chans
    ]
    alpha = small[3]
    rgb = np.stack(small[:3], axis=-1) / np.maximum(alpha, 1e-9)[..., None]
    out = np.concatenate([rgb, 255 * alpha[..., None]], axis=-1)
    return np.round(np.clip(out, 0, 255)).astype(np.uint8)


def apply_layer(images: np.ndarray, layer: np.ndarray) -> np.ndarray:
    """Images (n, size, size, 3) uint8 with the RGBA ``layer`` (size, size, 4) laid over them,
    "over" in sRGB as a browser composites an image over a canvas."""
    if layer.shape != (*images.shape[1:3], 4):
        raise ValueError(
            f"the layer's shape {layer.shape} does not fit images of shape {images.shape}"
        )
    a = layer[None, ..., 3:4].astype(np.float32) / 255
    out = images.astype(np.float32) * (1 - a) + layer[None, ..., :3].astype(np.float32) * a
    return np.round(out).astype(np.uint8)
