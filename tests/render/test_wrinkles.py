"""Wrinkles from the geometry (emogen.render.wrinkles): the strain is the textbook rotation-free
(Biot) strain U − I of the polar decomposition F = R U, and wrinkle detail lies where a shape
compresses the skin and nowhere it only turns or moves — for every shape of the model."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay
from scipy.spatial.transform import Rotation

from emogen.render.look import default_look
from emogen.render.scene import face_mesh
from emogen.render.wrinkles import (
    principal_compression,
    skin_strain_operator,
    strain_operator,
    wrinkle_amount,
)

LOOK = default_look()
START = float(LOOK.shader["WRINKLE_START"])


def _sheet(scale_cm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A flat 10 × 10 cm sheet (z = 0) triangulated by scipy, its UVs the positions / scale."""
    rng = np.random.default_rng(3)
    xy = np.r_[rng.uniform(0, 10, (60, 2)), [[0, 0], [10, 0], [0, 10], [10, 10]]]
    tri = Delaunay(xy).simplices
    return np.c_[xy, np.zeros(len(xy))], xy / scale_cm, tri


@settings(max_examples=25, deadline=None)
@given(
    m=st.lists(st.floats(-0.3, 0.3), min_size=4, max_size=4),
    scale=st.floats(5.0, 50.0),
    turn=st.lists(st.floats(-np.pi, np.pi), min_size=3, max_size=3),
)
def test_affine_map_has_its_textbook_biot_strain(
    m: list[float], scale: float, turn: list[float]
) -> None:
    """x → Rₛ (I + M) x on a flat sheet, Rₛ any rotation in space: the strain is U − I of
    scipy's polar decomposition I + M = R U at every vertex (in UV axes, here x and y),
    whatever the UV scale and the turn Rₛ."""
    rest, uv, tri = _sheet(scale)
    grad = np.eye(2) + np.array(m).reshape(2, 2)
    spin = Rotation.from_euler("xyz", turn).as_matrix()
    moved = np.c_[rest[:, :2] @ grad.T, np.zeros(len(rest))] @ spin.T + [0.4, -1.0, 2.0]
    eps = strain_operator(rest, uv, tri, len(rest)).strain(moved - rest)
    u = scipy.linalg.polar(grad)[1] - np.eye(2)
    np.testing.assert_allclose(eps, np.tile([u[0, 0], u[1, 1], u[0, 1]], (len(rest), 1)), atol=1e-5)
    # the principal compression is minus the smallest eigenvalue (numpy's eigvalsh)
    expected = max(-np.linalg.eigvalsh(u)[0], 0.0)
    np.testing.assert_allclose(principal_compression(eps), expected, atol=1e-5)


def test_rigid_motion_and_stretch_make_no_wrinkles_compression_does() -> None:
    rest, uv, tri = _sheet(10.0)
    op = strain_operator(rest, uv, tri, len(rest))
    turn = Rotation.from_euler("xyz", [70, -40, 120], degrees=True).as_matrix()
    rigid = rest @ turn.T + [0.3, -0.2, 0.5] - rest
    stretch = np.c_[0.2 * rest[:, :2], np.zeros(len(rest))]
    for d in (rigid, stretch):
        assert wrinkle_amount(op.strain(d), LOOK).max() == 0.0
    squeeze = (rest * [0.75, 1.0, 1.0]) @ turn.T - rest  # 25 % along x, turned
    assert wrinkle_amount(op.strain(squeeze), LOOK).min() > 0.2


def _local(edges: np.ndarray) -> np.ndarray:
    """(T, 2, 2) the two edge vectors (T, 3, 2) in an orthonormal frame of their plane."""
    e1, e2 = edges[:, :, 0], edges[:, :, 1]
    t1 = e1 / np.linalg.norm(e1, axis=1, keepdims=True)
    n = np.cross(e1, e2)
    t2 = np.cross(n / np.linalg.norm(n, axis=1, keepdims=True), t1)
    return np.stack([np.einsum("tk,tkj->tj", t1, edges), np.einsum("tk,tkj->tj", t2, edges)], 1)


def _smallest_stretch(rest: np.ndarray, moved: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(T,) the smallest exact principal stretch (deformed/rest length: numpy's SVD of each
    triangle's deformation gradient)."""

    def edges(p: np.ndarray) -> np.ndarray:
        return np.stack([p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]], axis=2)

    grad = _local(edges(moved)) @ np.linalg.inv(_local(edges(rest)))
    return np.asarray(np.linalg.svd(grad, compute_uv=False)[:, -1])


def _kabsch(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rotation R and shift t with R p + t closest to q (scipy's align_vectors)."""
    cp, cq = p.mean(axis=0), q.mean(axis=0)
    r = Rotation.align_vectors(q - cq, p - cp)[0].as_matrix()
    return r, cq - r @ cp


@pytest.mark.slow
def test_wrinkles_lie_where_each_shape_compresses_the_skin(ict_model) -> None:  # type: ignore[no-untyped-def]
    """For every shape at full weight:

    * every vertex that gets wrinkle detail has, among the triangles its strain averages
      (two rings), one that the shape compresses by more than ``WRINKLE_START`` (exact smallest
      principal stretch by SVD < 1 − start: the largest compression is a convex function of the
      strain, so an average cannot exceed its largest part);
    * the patch the shape moves, turned and shifted rigidly as the shape moves it on the whole
      (the best-fitting rotation, Kabsch), gets no strain and no detail inside (vertices whose
      two rings lie in the patch) — the chin under jawOpen, the cheeks under mouthSmile.
    """
    mesh = face_mesh(ict_model, LOOK)
    op = skin_strain_operator(ict_model, mesh, LOOK)
    src = mesh.source
    rest = ict_model.neutral[src].astype(np.float64)
    support = op.average.tocsr()
    n_detail = 0
    for s, name in enumerate(ict_model.shape_names):
        d = ict_model.deltas[s][src].astype(np.float64)
        amount = wrinkle_amount(op.strain(d), LOOK)
        squeezed = _smallest_stretch(rest, rest + d, op.triangles) < 1 - START + 1e-4
        has = np.flatnonzero(amount > 0)
        n_detail += len(has)
        for i in has:
            row = support.indices[support.indptr[i] : support.indptr[i + 1]]
            assert squeezed[row].any(), (name, i)
        moving = np.flatnonzero(np.abs(d).max(axis=1) > 1e-4)
        if len(moving) < 3:
            continue
        r, t = _kabsch(rest[moving], rest[moving] + d[moving])
        rigid = np.zeros_like(d)
        rigid[moving] = rest[moving] @ r.T + t - rest[moving]
        in_patch = np.zeros(len(src), dtype=bool)
        in_patch[moving] = True
        inside_tri = in_patch[op.triangles].all(axis=1)
        inside = np.asarray(support @ (~inside_tri).astype(float)).ravel() == 0
        inside &= np.asarray(support.sum(axis=1)).ravel() > 0
        eps = op.strain(rigid)
        assert np.abs(eps[inside]).max(initial=0.0) < 1e-4, name
        assert np.all(wrinkle_amount(eps, LOOK)[inside] == 0), name
    assert n_detail > 3_000  # the shapes do wrinkle the skin
