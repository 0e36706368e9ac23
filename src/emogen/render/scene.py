"""What the renderer draws of a face model: visible triangles and per-vertex shading attributes.

The browser viewer derives the same attributes from the GLB (``src/emogen/web/viewer/mesh.js``)
by the same rules:

* a vertex's part is the last ``look.json`` part whose regions hold it (else part 0, skin);
* an eye's centre is the least-squares sphere through its outer shell, its axis the mean
  direction of the ``eye_axis_vertices`` front-facing (+z) shell vertices farthest from that
  centre (the apex of the cornea bulge); a shell or ball vertex carries its unit direction from
  the centre in the eye's frame (x = normalise(up × axis), y = axis × x, z = axis);
* a fringe part's (eyelashes') opacity fades with the rest distance of a vertex to the nearest
  vertex of ``fringe_root``: ``opacity · (1 − smoothstep(0, fringe_cm, d))``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.spatial import cKDTree

from emogen.errors import ShapeError
from emogen.model.face import FaceModel
from emogen.model.geometry import triangle_incidence, vertex_normals
from emogen.model.io.obj import triangulate
from emogen.model.regions import ICT_VISIBLE_PARTS
from emogen.render.look import Look


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def sphere_centre(points: np.ndarray) -> np.ndarray:
    """Least-squares sphere centre of points (n, 3): solve 2 p·c + (r² − |c|²) = |p|²."""
    p = np.asarray(points, dtype=np.float64)
    a = np.c_[2 * p, np.ones(len(p))]
    sol, *_ = np.linalg.lstsq(a, (p**2).sum(1), rcond=None)
    return np.asarray(sol[:3])


def eye_frame(shell: np.ndarray, n_axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Rest frame of an eye from its outer shell's vertices (n, 3).

    Returns (centre (3,), rotation (3, 3) whose rows are the eye's x, y and z = axis).
    """
    centre = sphere_centre(shell)
    d = shell.astype(np.float64) - centre
    r = np.linalg.norm(d, axis=1)
    r[d[:, 2] <= 0] = -1.0  # the cornea faces forward (+z)
    top = np.argsort(-r, kind="stable")[:n_axis]
    z = (d[top] / r[top, None]).mean(0)
    z /= np.linalg.norm(z)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    return centre, np.stack([x, np.cross(z, x), z])


def smoothstep(e0: float, e1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)


def visible_polygons(model: FaceModel) -> np.ndarray:
    """Polygons the renderer draws: ICT's visible parts (as the GLB), else every polygon."""
    if all(p in model.regions for p in ICT_VISIBLE_PARTS):
        regions = [model.regions[p] for p in ICT_VISIBLE_PARTS]
        return np.unique(np.concatenate([np.arange(r.p_start, r.p_stop) for r in regions]))
    return np.arange(len(model.polygons))


@dataclass(frozen=True)
class DrawGroup:
    """A run of ``FaceMesh.triangles`` drawn with the same state."""

    first: int  # first triangle
    count: int  # triangles
    double_sided: bool
    cutout: bool
    blended: bool


@dataclass(frozen=True, eq=False)
class FaceMesh:
    """Static render data of a model.

    triangles : (T, 3) int32 visible triangles in the model's vertex numbering, ordered into
        ``groups``: single-sided opaque parts first (early depth test), then double-sided,
        cutouts, and blended parts last
    part : (V,) float32 part code; albedo : (V, 3) float32 linear RGB
    surface : (V, 4) float32 (specular, shininess, cavity, opacity)
    eye : (V, 4) float32 unit rest direction in the eye frame and side (0: not an eye)
    """

    n_vertices: int
    triangles: np.ndarray
    part: np.ndarray
    albedo: np.ndarray
    surface: np.ndarray
    eye: np.ndarray
    incidence: sparse.csr_matrix  # (V, T): vertex normal = Σ adjacent face normals
    groups: tuple[DrawGroup, ...]
    #: What the GPU draws: UV seams split vertices, as in the GLB. ``source`` (R,) is the model
    #: vertex of each drawn vertex, ``uv`` (R, 2) its glTF UV (u in tiles, v down), and
    #: ``drawn_triangles`` (T, 3) the triangles in that numbering (same order as ``triangles``).
    source: np.ndarray
    uv: np.ndarray
    drawn_triangles: np.ndarray

    def normals(self, vertices: np.ndarray) -> np.ndarray:
        """Area-weighted unit vertex normals: vertices (B, V, 3) → (B, V, 3) float32."""
        v = np.asarray(vertices, dtype=np.float32)
        if v.ndim != 3 or v.shape[1] != self.n_vertices:
            raise ShapeError(f"vertices must be (n_faces, {self.n_vertices}, 3); got {v.shape}")
        return vertex_normals(v, self.triangles, dtype=np.float32, incidence=self.incidence)


def _part_codes(model: FaceModel, look: Look) -> np.ndarray:
    code = np.zeros(model.n_vertices, dtype=np.int64)
    for i, p in enumerate(look.parts):
        for name in p.regions:
            if name in model.regions:
                code[model.regions[name].vertices] = i
    return code


def _eye_directions(model: FaceModel, look: Look) -> np.ndarray:
    eye = np.zeros((model.n_vertices, 4), dtype=np.float64)
    for e in look.eyes:
        if not {e.shell, e.ball} <= set(model.regions):
            continue
        centre, frame = eye_frame(
            model.neutral[model.regions[e.shell].vertices], look.eye_axis_vertices
        )
        for name in (e.shell, e.ball):
            sl = model.regions[name].vertices
            d = (model.neutral[sl].astype(np.float64) - centre) @ frame.T
            eye[sl, :3] = d / np.linalg.norm(d, axis=1, keepdims=True)
            eye[sl, 3] = e.side
    return eye


def _lid_margin(model: FaceModel, look: Look, code: np.ndarray, drawn: np.ndarray) -> np.ndarray:
    """(V, 4) the ``eye`` attribute of skin vertices that lie on an eyeball (look.json
    ``lid_margin``): x the lower lid's wet margin, y the inner corner; w stays 0 (not an eye).
    Distances go to the shell's drawn vertices only, as the viewer (mesh.js) sees them."""
    lm = look.lid_margin
    out = np.zeros((model.n_vertices, 4), dtype=np.float64)
    if not lm:
        return out
    skin = np.flatnonzero(code == int(look.shader["PART_SKIN"]))
    for e in look.eyes:
        if not {e.shell, e.ball} <= set(model.regions):
            continue
        centre, frame = eye_frame(
            model.neutral[model.regions[e.shell].vertices], look.eye_axis_vertices
        )
        shell = np.intersect1d(model.regions[e.shell].vertex_indices(), drawn)
        p = model.neutral[skin].astype(np.float64)
        near = np.linalg.norm(p - centre, axis=1) < 2.5
        dist, _ = cKDTree(model.neutral[shell]).query(p[near])
        u = (p[near] - centre) @ frame.T
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        on = 1.0 - smoothstep(lm["near_cm"], lm["far_cm"], dist)
        nasal = -u[:, 0] if e.side == 1 else u[:, 0]
        out[skin[near], 0] = on * np.clip(-u[:, 1] / lm["lower_fade"], 0.0, 1.0)
        out[skin[near], 1] = on * smoothstep(lm["caruncle_from"], lm["caruncle_full"], nasal)
    return out


def _opacity(model: FaceModel, look: Look, code: np.ndarray) -> np.ndarray:
    alpha = np.array([p.opacity for p in look.parts])[code]
    root = model.regions.get(look.fringe_root)
    for i, p in enumerate(look.parts):
        if p.fringe_cm <= 0 or root is None:
            continue
        members = np.flatnonzero(code == i)
        if len(members) == 0:
            continue
        dist, _ = cKDTree(model.neutral[root.vertices]).query(model.neutral[members])
        alpha[members] = p.opacity * (1 - smoothstep(0.0, p.fringe_cm, dist))
    return alpha


def _grouped(
    triangles: np.ndarray, code: np.ndarray, look: Look
) -> tuple[np.ndarray, tuple[DrawGroup, ...]]:
    """Order of the triangles by draw state (stable within a state), keyed by their first
    corner's part, and the groups of that order."""
    flags = np.array([[p.blended, p.cutout, p.double_sided] for p in look.parts], dtype=np.int64)
    key = (flags @ [4, 2, 1])[code[triangles[:, 0]]]
    order = np.argsort(key, kind="stable")
    groups, first = [], 0
    for k, n in enumerate(np.bincount(key, minlength=8)):
        if n:
            groups.append(DrawGroup(first, int(n), bool(k & 1), bool(k & 2), bool(k & 4)))
        first += int(n)
    return order, tuple(groups)


def _uv_corners(model: FaceModel, owner: np.ndarray) -> np.ndarray:
    """(T, 3) UV ids of the triangles of :func:`triangulate` (−1: none)."""
    if len(model.uvs) == 0 or model.polygon_uvs.shape != model.polygons.shape:
        return np.full((len(owner), 3), -1, dtype=np.int64)
    second = np.r_[False, owner[1:] == owner[:-1]]
    puv = model.polygon_uvs[owner]
    return np.where(second[:, None], puv[:, [0, 2, 3]], puv[:, [0, 1, 2]]).astype(np.int64)


def _split_seams(
    model: FaceModel, triangles: np.ndarray, uv_ids: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(source (R,), uv (R, 2) glTF convention, drawn triangles (T, 3)): one drawn vertex per
    distinct (vertex, UV) corner pair, ordered by vertex then UV."""
    pairs = np.stack([triangles.reshape(-1).astype(np.int64), uv_ids.reshape(-1)], 1)
    unique, inverse = np.unique(pairs, axis=0, return_inverse=True)
    uv = np.zeros((len(unique), 2), dtype=np.float32)
    has = unique[:, 1] >= 0
    uv[has] = model.uvs[unique[has, 1]]
    uv[has, 1] = 1.0 - uv[has, 1]
    drawn = inverse.reshape(-1, 3).astype(np.int32)
    return unique[:, 0].astype(np.int32), uv, np.ascontiguousarray(drawn)


def face_mesh(model: FaceModel, look: Look) -> FaceMesh:
    """Triangles and per-vertex shading attributes of ``model`` under ``look``."""
    tris, owner = triangulate(model.polygons)
    keep = np.isin(owner, visible_polygons(model))
    code = _part_codes(model, look)
    uv_ids = _uv_corners(model, owner)[keep]
    tris = tris[keep]
    order, groups = _grouped(tris, code, look)
    triangles = np.ascontiguousarray(tris[order], dtype=np.int32)
    source, uv, drawn = _split_seams(model, triangles, uv_ids[order])
    albedo = np.array([srgb_to_linear(np.array(p.albedo_srgb)) for p in look.parts])[code]
    surface = np.c_[
        np.array([[p.specular, p.shininess, p.cavity] for p in look.parts])[code],
        _opacity(model, look, code),
    ]
    incidence = triangle_incidence(triangles, model.n_vertices, np.float32)
    return FaceMesh(
        n_vertices=model.n_vertices,
        triangles=triangles,
        part=code.astype(np.float32),
        albedo=albedo.astype(np.float32),
        surface=surface.astype(np.float32),
        eye=(_eye_directions(model, look) + _lid_margin(model, look, code, source)).astype(
            np.float32
        ),
        incidence=incidence,
        groups=groups,
        source=source,
        uv=uv,
        drawn_triangles=drawn,
    )
