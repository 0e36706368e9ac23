"""Painting the skin atlas: tone, regional colour, mottling, lips, brows, scalp hair, stubble.

Every layer is a function of a texel's rest position (cm) — computed once per identity by
:mod:`emogen.appearance.layout` — so features sit where the geometry puts them and move with
every shape. Colours are mixed in linear RGB; the result is an sRGB ``uint8`` atlas.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib.path import Path as PolyPath
from scipy import ndimage

from emogen.appearance.features import Brow, FaceFeatures
from emogen.appearance.params import MONK_SWATCHES, Appearance, hex_to_srgb


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


def monk_linear(tone: float) -> np.ndarray:
    """Linear RGB of Monk tone ``tone`` ∈ [1, 10] (fractions interpolate neighbouring swatches)."""
    sw = np.array([srgb_to_linear(np.array(hex_to_srgb(h))) for h in MONK_SWATCHES])
    return np.array([np.interp(tone, np.arange(1, 11), sw[:, k]) for k in range(3)])


def smoothstep(e0: float, e1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((np.asarray(x) - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)


@dataclass(frozen=True)
class Texels:
    """Per-texel inputs of the painters: the n texels inside the UV islands."""

    pos: np.ndarray  # (n, 3) rest position, cm
    normal: np.ndarray  # (n, 3) rest unit normal
    cyl: np.ndarray  # (n, 2) cylindrical (s, y), cm
    theta: np.ndarray  # (n,) degrees around the head axis, 0 in front
    face: np.ndarray  # (n,) bool: texel of the face region (else head and neck, eye sockets)
    lids: np.ndarray  # (n,) bool: texel of the eye sockets (the inner lids)
    cavity: np.ndarray  # (n,) concavity in [0, 1]
    shape: tuple[int, int]  # (H, W) of the atlas
    index: np.ndarray  # (n,) flat atlas index of each texel (the covered ones)
    corners: np.ndarray  # (n, 3) vertices of each texel's triangle
    bary: np.ndarray  # (n, 3) the texel's barycentric weights in it
    vertex_pos: np.ndarray  # (V, 3) rest positions
    vertex_normal: np.ndarray  # (V, 3) rest unit normals

    def from_vertices(self, values: np.ndarray) -> np.ndarray:
        """Per-vertex values (V, …) → per-texel (n, …), linearly inside each triangle (for
        smooth fields: painting them at the vertices costs 40× less than at the texels)."""
        return np.einsum("nk,nk...->n...", self.bary, np.asarray(values)[self.corners])


def texel_noise(t: Texels, rng: np.random.Generator, sigma_texels: float = 0.7) -> np.ndarray:
    """Fine grain (hairs, follicles) in texture space: unit-variance noise about one texel wide."""
    white = rng.standard_normal(t.shape).astype(np.float32)
    field = ndimage.gaussian_filter(white, sigma_texels, mode="wrap")
    return (field / max(float(field.std()), 1e-12)).reshape(-1)[t.index]


class NoiseField:
    """Smooth random fields over the cylindrical (s, y) plane, sampled at texels."""

    def __init__(self, rng: np.random.Generator, step: float = 0.04) -> None:
        self.rng, self.step = rng, step
        self.s0, self.y0 = -32.0, -24.0
        self.shape = (int(44 / step), int(64 / step))  # y rows, s columns

    def sample(
        self, cyl: np.ndarray, sigma_cm: tuple[float, float], step: float | None = None
    ) -> np.ndarray:
        """Zero-mean, unit-variance noise smoothed by ``sigma_cm`` (along s, along y)."""
        st = step or max(self.step, min(sigma_cm) / 2)
        shape = (int(44 / st), int(64 / st))
        white = self.rng.standard_normal(shape).astype(np.float32)
        field = ndimage.gaussian_filter(white, (sigma_cm[1] / st, sigma_cm[0] / st), mode="wrap")
        field /= max(float(field.std()), 1e-12)
        rows = (cyl[:, 1] - self.y0) / st
        cols = (cyl[:, 0] - self.s0) / st
        return ndimage.map_coordinates(field, [rows, cols], order=1, mode="nearest")


def _gauss(pos: np.ndarray, centre: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """exp(−½‖(pos − centre) / radius‖²), evaluated only within 4 radii (0 beyond)."""
    out = np.zeros(len(pos))
    near = np.all(np.abs(pos - centre) < 4 * radius, axis=1)
    d = (pos[near] - centre) / radius
    out[near] = np.exp(-0.5 * (d**2).sum(-1))
    return out


def regional_maps(t: Texels, f: FaceFeatures) -> tuple[np.ndarray, np.ndarray]:
    """(redness, periorbital) weights in [0, 1] per texel (smooth: made at the vertices)."""
    red, peri = _regional_at(t.vertex_pos, t.vertex_normal, f)
    return t.from_vertices(red), t.from_vertices(peri)


def _regional_at(
    pos: np.ndarray, normal: np.ndarray, f: FaceFeatures
) -> tuple[np.ndarray, np.ndarray]:
    lm = f.landmarks
    red = np.zeros(len(pos))
    front = normal[:, 2] > -0.2
    for side in (-1, 1):
        eye = f.eye_centres[0 if side < 0 else 1]
        cheek = np.array([eye[0] * 1.08, eye[1] - 2.9, eye[2] + 0.2])
        red += 0.9 * _gauss(pos, cheek, np.array([1.9, 1.6, 3.0])) * front
        ear = np.array([side * (abs(lm[0, 0]) + 1.2), lm[0, 1] - 1.0, lm[0, 2] - 3.2])
        red += 0.8 * _gauss(pos, ear, np.array([1.2, 2.6, 1.6]))
    red += 0.9 * _gauss(pos, lm[30], np.array([1.0, 0.9, 1.2]))  # nose tip
    red += (
        0.35 * _gauss(pos, lm[8] + np.array([0.0, 0.8, 0.0]), np.array([1.6, 1.2, 2.0])) * front
    )  # chin
    red += (
        0.25 * _gauss(pos, lm[27] + np.array([0.0, 3.5, 0.0]), np.array([3.5, 2.0, 3.0])) * front
    )  # brow
    peri = np.zeros(len(pos))
    for k, eye in enumerate(f.eye_centres):
        ids = range(36, 42) if k == 0 else range(42, 48)
        width = float(np.ptp(lm[list(ids), 0]))
        under = eye + np.array([0.0, -0.75, 0.0])
        peri += _gauss(pos, under, np.array([width * 0.55, 0.45, 2.0]))
        lid = eye + np.array([0.0, 0.55, 0.0])
        peri += 0.7 * _gauss(pos, lid, np.array([width * 0.6, 0.45, 2.0]))
    return np.clip(red, 0, 1), np.clip(peri, 0, 1) * front


def lip_mask(t: Texels, f: FaceFeatures, px_cm: float) -> tuple[np.ndarray, np.ndarray]:
    """(vermilion coverage, lip-line weight): inside the outer lip contour, soft over one
    texel; the line is a thin band just inside the border."""
    path = PolyPath(f.lip_outline)
    cand = (t.pos[:, 2] > f.lip_front_z) & t.face
    cand &= np.abs(t.pos[:, 0]) < np.abs(f.lip_outline[:, 0]).max() + 0.3
    idx = np.flatnonzero(cand)
    xy = t.pos[idx, :2]
    inside = path.contains_points(xy)
    # distance to the contour (polyline, densely sampled)
    pts = f.lip_outline
    from scipy.spatial import cKDTree

    dense = np.concatenate(
        [np.linspace(pts[i], pts[(i + 1) % len(pts)], 6, endpoint=False) for i in range(len(pts))]
    )
    dist, _ = cKDTree(dense).query(xy)
    signed = np.where(inside, dist, -dist)
    soft = max(px_cm * 0.75, 0.02)
    cover = np.zeros(len(t.pos))
    cover[idx] = smoothstep(-soft, soft, signed)
    line = np.zeros(len(t.pos))
    line[idx] = np.exp(-0.5 * ((signed - 0.045) / 0.035) ** 2) * (signed > -soft)
    return cover, line


def _brow_strokes(
    brow: Brow, look: Appearance, rng: np.random.Generator, step: float
) -> tuple[np.ndarray, tuple[float, float]]:
    """Hair strokes of one brow drawn on a fine (s, y) canvas: (coverage image, origin)."""
    line = brow.line
    seg = np.linalg.norm(np.diff(line, axis=0), axis=1)
    arc = np.r_[0.0, np.cumsum(seg)]
    length = arc[-1]
    heights = brow.height * look.brow_thickness
    area = float(np.trapezoid(heights, arc))
    n_hairs = int(420 * area * look.brow_density)
    lo = line.min(0) - 2.0
    hi = line.max(0) + 2.0
    shape = (int((hi[1] - lo[1]) / step) + 1, int((hi[0] - lo[0]) / step) + 1)
    canvas = np.zeros(shape, dtype=np.float32)
    if n_hairs == 0:
        return canvas, (float(lo[0]), float(lo[1]))
    # roots: along the brow weighted by band height, across it with thinning edges
    a = rng.uniform(0, length, size=4 * n_hairs)
    h = np.interp(a, arc, heights)
    keep = rng.uniform(0, heights.max(), size=len(a)) < h
    a, h = a[keep][:n_hairs], h[keep][:n_hairs]
    n = len(a)
    across = rng.uniform(-0.5, 0.5, size=n)
    thin = rng.uniform(size=n) < 1.0 - 0.7 * smoothstep(0.3, 0.5, np.abs(across))
    a, h, across = a[thin], h[thin], across[thin]
    n = len(a)
    centre = np.c_[np.interp(a, arc, line[:, 0]), np.interp(a, arc, line[:, 1])]
    tangent = np.c_[
        np.interp(a, arc, np.gradient(line[:, 0])), np.interp(a, arc, np.gradient(line[:, 1]))
    ]
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.c_[-tangent[:, 1], tangent[:, 0]] * np.sign(tangent[:, 0:1] * brow.side + 1e-9)
    normal *= np.where(normal[:, 1:2] < 0, -1, 1)  # pointing up
    root = centre + normal * (across * h)[:, None] - tangent * 0.15
    # growth angle from the brow tangent: steep up at the head, along it in the body, down in the tail
    u = a / length
    angle = np.radians(np.interp(u, [0.0, 0.1, 0.3, 0.7, 1.0], [70.0, 45.0, 18.0, 8.0, -6.0]))
    angle += np.radians(rng.normal(0, 7.0, size=n))
    direction = (
        tangent * np.cos(angle)[:, None] + np.c_[0 * angle, np.ones(n)] * np.sin(angle)[:, None]
    )
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    hair_len = rng.uniform(0.45, 0.85, size=n) * np.interp(u, [0, 0.15, 1], [0.65, 1.0, 0.8])
    bend = rng.normal(0, 0.12, size=n)  # curvature, cm of sideways bow
    k = np.linspace(0, 1, 48)
    side_dir = np.c_[-direction[:, 1], direction[:, 0]]
    pts = (
        root[:, None, :]
        + direction[:, None, :] * (hair_len[:, None] * k)[..., None]
        + side_dir[:, None, :] * (bend[:, None] * k * k)[..., None]
    )
    weight = np.broadcast_to((1.0 - 0.6 * k**2)[None, :], pts.shape[:2])  # thinner tips
    rows = ((pts[..., 1] - lo[1]) / step).astype(np.int64).ravel()
    cols = ((pts[..., 0] - lo[0]) / step).astype(np.int64).ravel()
    ok = (rows >= 0) & (rows < shape[0]) & (cols >= 0) & (cols < shape[1])
    np.add.at(canvas, (rows[ok], cols[ok]), weight.ravel()[ok])
    return canvas, (float(lo[0]), float(lo[1]))


def brow_coverage(
    t: Texels, f: FaceFeatures, look: Appearance, rng: np.random.Generator, px_cm: float
) -> np.ndarray:
    """Eyebrow hair coverage in [0, 1] per texel."""
    out = np.zeros(len(t.pos))
    step = 0.004
    front = (t.normal[:, 2] > 0.0) & t.face
    for brow in f.brows:
        canvas, (s0, y0) = _brow_strokes(brow, look, rng, step)
        # A hair is ~0.01 cm wide: a stroke sample deposits that much cover over one step.
        sigma = max(px_cm * 0.5, 0.008) / step
        density = ndimage.gaussian_filter(canvas, sigma) * (0.012 / step) * 1.0
        rows = (t.cyl[:, 1] - y0) / step
        cols = (t.cyl[:, 0] - s0) / step
        inside = (
            front
            & (rows >= 0)
            & (rows < canvas.shape[0] - 1)
            & (cols >= 0)
            & (cols < canvas.shape[1] - 1)
        )
        idx = np.flatnonzero(inside)
        d = ndimage.map_coordinates(density, [rows[idx], cols[idx]], order=1)
        out[idx] = np.maximum(out[idx], 1.0 - np.exp(-3.0 * d))
    return out


def hairline_height(theta: np.ndarray, f: FaceFeatures, look: Appearance) -> np.ndarray:
    """Scalp hairline height (cm) by angle around the head (degrees, 0 in front)."""
    forehead = 3.7 * look.hairline
    front = f.brow_top + forehead
    eye = float(f.eye_centres[:, 1].mean())
    recess = 1.4 * max(look.hairline - 1.0, 0.0) / 0.3
    ang = [0.0, 20.0, 38.0, 52.0, 64.0, 74.0, 84.0, 96.0, 112.0, 130.0, 180.0]
    ys = [
        front,
        front + 0.25,
        front + 0.6 + recess,
        front - 1.2 + 0.5 * recess,
        eye + 2.8,
        eye - 0.2,
        eye + 0.6,
        eye + 3.4,
        eye + 0.5,
        eye - 6.0,
        eye - 8.5,
    ]
    return np.interp(np.abs(theta), ang, ys)


def ear_mask(t: Texels, f: FaceFeatures) -> np.ndarray:
    """Texels of the outer ears (never hair), by position behind the jaw's top landmarks."""
    lm = f.landmarks
    out = np.zeros(len(t.pos), dtype=bool)
    for side, k in ((-1, 0), (1, 16)):
        root = lm[k]
        out |= (
            t.face
            & (side * t.pos[:, 0] > abs(root[0]) - 0.2)
            & (t.pos[:, 2] < root[2] + 0.8)
            & (t.pos[:, 1] < root[1] + 3.6)
            & (t.pos[:, 1] > root[1] - 5.8)
        )
    return out


def scalp_coverage(
    t: Texels, f: FaceFeatures, look: Appearance, noise: NoiseField, px_cm: float
) -> np.ndarray:
    """Short-cropped scalp hair coverage in [0, 1] per texel (0 everywhere for ``hair='none'``)."""
    if look.hair == "none" or look.hair_density == 0:
        return np.zeros(len(t.pos))
    edge = hairline_height(t.theta, f, look) + 0.25 * noise.sample(t.cyl, (0.6, 0.6))
    above = t.pos[:, 1] - edge
    ramp = smoothstep(-0.1, 0.9, above)
    fine = texel_noise(t, noise.rng)  # individual hairs at the hairline
    sparse_edge = smoothstep(-1.2, 1.2, fine + 3.0 * (ramp - 0.5))
    cover = ramp * sparse_edge * look.hair_density
    cover[ear_mask(t, f)] = 0.0
    return np.clip(cover, 0, 1)


def beard_mask(t: Texels, f: FaceFeatures) -> np.ndarray:
    """Beard area in [0, 1]: jaw, chin, upper lip and cheeks below the cheekbones."""
    lm = f.landmarks
    ax = np.abs(t.pos[:, 0])
    mouth_y = lm[51, 1]
    xs = [0.0, 1.0, 2.0, 3.0, 4.5, 6.0, 7.3]
    ys = [
        lm[33, 1] - 0.25,
        lm[33, 1] - 0.35,
        mouth_y + 0.3,
        mouth_y + 0.6,
        lm[30, 1] - 0.6,
        lm[0, 1] - 1.2,
        lm[0, 1] + 0.5,
    ]
    top = np.interp(ax, xs, ys)
    soft = smoothstep(-0.3, 1.2, top - t.pos[:, 1])
    bottom = lm[8, 1] - 3.0
    soft *= smoothstep(bottom - 1.5, bottom + 0.5, t.pos[:, 1])
    soft *= (t.pos[:, 2] > lm[0, 2] - 3.0) & ~ear_mask(t, f)
    return soft


def paint_albedo(
    t: Texels, f: FaceFeatures, look: Appearance, irradiance: float, px_cm: float
) -> np.ndarray:
    """The skin atlas as linear RGB (n, 3)."""
    rng = np.random.default_rng(look.seed)
    noise = NoiseField(np.random.default_rng(rng.integers(2**63)))
    tone = (look.skin_tone - 1) / 9
    base = monk_linear(look.skin_tone) / irradiance
    col = np.tile(base, (len(t.pos), 1))
    # mottling: blotches and fine variation of lightness and hue
    m1 = noise.sample(t.cyl, (1.5, 1.5))
    m2 = noise.sample(t.cyl, (0.25, 0.25))
    m3 = noise.sample(t.cyl, (0.6, 0.6))
    col *= (1 + 0.025 * m1 + 0.02 * m2)[:, None]
    col *= np.c_[1 + 0.02 * m3, np.ones(len(m3)), 1 - 0.02 * m3]
    # regional colour: redder cheeks, nose tip, ears, chin; darker around the eyes
    red, peri = regional_maps(t, f)
    r = (red + 0.35 * (1 - tone)) * look.redness * (1 - 0.5 * tone)
    col *= np.c_[1 + 0.10 * r, 1 - 0.10 * r, 1 - 0.08 * r]
    col *= 1 - peri[:, None] * np.array([0.13, 0.15, 0.12]) * (0.8 + 0.4 * tone)
    # creases read darker (baked concavity of the rest mesh)
    col *= (1 - 0.35 * t.cavity)[:, None]
    # inner lids: the wet, redder lid margin
    col[t.lids] *= (1 - tone) * np.array([0.92, 0.70, 0.70]) + tone * np.array([0.85, 0.75, 0.78])
    # stubble shadow
    if look.beard_shadow > 0:
        stubble = 0.55 + 0.45 * smoothstep(-1.0, 1.5, texel_noise(t, rng))
        b = beard_mask(t, f) * look.beard_shadow * stubble
        col *= 1 - b[:, None] * np.array([0.22, 0.21, 0.16])
    # lips: vermilion with a clear border line
    cover, line = lip_mask(t, f, px_cm)
    tint = (1 - tone) * np.array([0.98, 0.52, 0.55]) + tone * np.array([0.80, 0.62, 0.72])
    strength = np.clip(cover * look.lip_colour, 0, 1.5)
    lip = col * tint * (1 - 0.06 * m2[:, None]) * (1 - look.lip_depth)
    col = col + (lip - col) * np.minimum(strength, 1.0)[:, None]
    col *= (1 - 0.22 * line * min(look.lip_colour, 1.0))[:, None]
    # scalp hair, then brows on top
    hair_lin = srgb_to_linear(np.array(hex_to_srgb(look.hair_colour)))
    hair = scalp_coverage(t, f, look, noise, px_cm)
    grain = 0.75 + 0.5 * smoothstep(-2, 2, texel_noise(t, rng, 0.5))
    col = col + (hair_lin * grain[:, None] - col) * hair[:, None]
    brow_lin = srgb_to_linear(np.array(hex_to_srgb(look.brow_colour)))
    brow = brow_coverage(t, f, look, np.random.default_rng(rng.integers(2**63)), px_cm)
    col = col + (brow_lin - col) * brow[:, None]
    return np.clip(col, 0, 1)
