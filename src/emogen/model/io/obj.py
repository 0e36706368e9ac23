"""Fast, strict reading of Wavefront OBJ files as ICT-FaceKit writes them.

Vertex positions are read as one block with numpy; the slow line-by-line scan runs only to
name the offending line when the fast path finds something malformed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from emogen.errors import ModelFileError


def _first_bad_line(path: Path, text: bytes, prefix: bytes, n_fields: int) -> str:
    """Name the first malformed ``prefix`` line (1-based line number) for an error message."""
    for lineno, raw in enumerate(text.split(b"\n"), start=1):
        if not raw.startswith(prefix):
            continue
        parts = raw.split()
        try:
            if len(parts) < n_fields + 1:
                raise ValueError
            [float(p) for p in parts[1 : n_fields + 1]]
        except ValueError:
            line = raw.decode("utf-8", "replace").strip()
            want = " ".join(["x", "y", "z"][:n_fields]) if n_fields == 3 else "u v"
            return f"{path}:{lineno}: malformed line {line!r}: expected '{prefix.decode().strip()} {want}'"
    return f"{path}: malformed '{prefix.decode().strip()}' block"


def _block_floats(path: Path, text: bytes, prefix: bytes, n_fields: int) -> np.ndarray:
    """All ``prefix`` lines of ``text`` as an (n, n_fields) float64 array, in file order."""
    total = text.count(b"\n" + prefix) + int(text.startswith(prefix))
    if total == 0:
        return np.zeros((0, n_fields))
    run = re.compile(rb"(?m)^(?:" + re.escape(prefix) + rb"[^\n]*(?:\n|$))+")
    match = run.search(text)
    block = match.group(0) if match else b""
    if block.count(b"\n" + prefix) + 1 == total:
        tokens = block.split()
    else:
        # Not one contiguous block (another exporter): gather the lines one by one.
        tokens = b" ".join(ln for ln in text.split(b"\n") if ln.startswith(prefix)).split()
    width = n_fields + 1
    arr = np.array(tokens)
    if arr.size % width != 0 or arr.size // width != total:
        raise ModelFileError(_first_bad_line(path, text, prefix, n_fields))
    arr = arr.reshape(-1, width)
    if not np.all(arr[:, 0] == prefix.strip()):
        raise ModelFileError(_first_bad_line(path, text, prefix, n_fields))
    try:
        values = arr[:, 1:].astype(np.float64)
    except ValueError:
        raise ModelFileError(_first_bad_line(path, text, prefix, n_fields)) from None
    if not np.all(np.isfinite(values)):
        raise ModelFileError(_first_bad_line(path, text, prefix, n_fields) + " (non-finite value)")
    return values


def read_bytes(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise ModelFileError(f"model file is missing: {path}") from None
    except OSError as exc:
        raise ModelFileError(f"cannot read model file {path}: {exc.strerror}") from None


def parse_vertices(path: Path, text: bytes | None = None) -> np.ndarray:
    """The ``v x y z`` positions of an OBJ file, (n_vertices, 3) float64, in file order."""
    if text is None:
        text = read_bytes(path)
    verts = _block_floats(path, text, b"v ", 3)
    if len(verts) == 0:
        raise ModelFileError(f"{path}: no vertex ('v x y z') lines found: not an OBJ mesh?")
    return verts


@dataclass(frozen=True)
class ObjTopology:
    """Polygons of an OBJ mesh (triangles and quads), their UVs and material groups."""

    polygons: np.ndarray  # (P, 4) int32 vertex indices, -1 pads a triangle's 4th corner
    polygon_uvs: np.ndarray  # (P, 4) int32 indices into uvs, -1 pads
    uvs: np.ndarray  # (T, 2) float32
    polygon_material: np.ndarray  # (P,) int16 index into materials
    materials: tuple[str, ...]


def parse_topology(path: Path, n_vertices: int, text: bytes | None = None) -> ObjTopology:
    """Faces (``f a/ta b/tb c/tc [d/td]``), UVs and ``usemtl`` groups of an OBJ file."""
    if text is None:
        text = read_bytes(path)
    uvs = _block_floats(path, text, b"vt ", 2).astype(np.float32)
    polys: list[list[int]] = []
    puvs: list[list[int]] = []
    mats: list[int] = []
    materials: list[str] = []
    current = -1
    for lineno, raw in enumerate(text.split(b"\n"), start=1):
        if raw.startswith(b"usemtl"):
            name = raw[6:].strip().decode("utf-8", "replace")
            if name not in materials:
                materials.append(name)
            current = materials.index(name)
            continue
        if not raw.startswith(b"f "):
            continue
        corners = raw.split()[1:]
        if len(corners) not in (3, 4):
            raise ModelFileError(
                f"{path}:{lineno}: face has {len(corners)} corners; expected 3 or 4 (triangles or quads)"
            )
        vi: list[int] = []
        ti: list[int] = []
        try:
            for c in corners:
                fields = c.split(b"/")
                vi.append(int(fields[0]) - 1)
                ti.append(int(fields[1]) - 1 if len(fields) > 1 and fields[1] else -1)
        except ValueError:
            line = raw.decode("utf-8", "replace").strip()
            raise ModelFileError(f"{path}:{lineno}: malformed face line {line!r}") from None
        if min(vi) < 0 or max(vi) >= n_vertices:
            raise ModelFileError(
                f"{path}:{lineno}: face refers to vertex {max(vi) + 1 if max(vi) >= n_vertices else min(vi) + 1}; "
                f"the mesh has {n_vertices} vertices"
            )
        if len(vi) == 3:
            vi.append(-1)
            ti.append(-1)
        polys.append(vi)
        puvs.append(ti)
        mats.append(max(current, 0))
    if not polys:
        raise ModelFileError(f"{path}: no face ('f ...') lines found")
    polygons = np.asarray(polys, dtype=np.int32)
    polygon_uvs = np.asarray(puvs, dtype=np.int32)
    if polygon_uvs.max() >= len(uvs):
        raise ModelFileError(
            f"{path}: a face refers to UV {polygon_uvs.max() + 1}; only {len(uvs)} 'vt' lines"
        )
    return ObjTopology(
        polygons=polygons,
        polygon_uvs=polygon_uvs,
        uvs=uvs,
        polygon_material=np.asarray(mats, dtype=np.int16),
        materials=tuple(materials) or ("default",),
    )


def triangulate(polygons: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split quads (a, b, c, d) into (a, b, c) and (a, c, d).

    Returns ``triangles (T, 3) int32`` and ``triangle_polygon (T,)``, the polygon each came from.
    """
    quads = polygons[:, 3] >= 0
    first = polygons[:, :3]
    second = polygons[quads][:, [0, 2, 3]]
    tris = np.concatenate([first, second]).astype(np.int32)
    owner = np.concatenate([np.arange(len(polygons)), np.flatnonzero(quads)])
    order = np.argsort(owner, kind="stable")
    return np.ascontiguousarray(tris[order]), owner[order].astype(np.int32)


def write_obj(
    path: Path,
    vertices: np.ndarray,
    polygons: np.ndarray,
    header: str = "",
    *,
    uvs: np.ndarray | None = None,
    polygon_uvs: np.ndarray | None = None,
    polygon_material: np.ndarray | None = None,
    materials: tuple[str, ...] = (),
) -> None:
    """Write one mesh as OBJ: ``v`` lines, ``vt`` lines, then ``f`` lines (1-based, quads kept).

    With ``uvs`` and ``polygon_uvs`` the faces carry UV indices (``f a/ta b/tb c/tc``); with
    ``polygon_material`` and ``materials`` a ``usemtl`` line starts each run of one material.
    """
    out = [f"# {h}" if h else "#" for h in header.splitlines()]
    out.extend("v {:.6f} {:.6f} {:.6f}".format(*v) for v in np.asarray(vertices).tolist())
    with_uv = uvs is not None and polygon_uvs is not None
    if with_uv:
        out.extend("vt {:.6f} {:.6f}".format(*t) for t in np.asarray(uvs).tolist())
    tex_rows = (np.asarray(polygon_uvs) + 1).tolist() if with_uv else []
    mats = polygon_material.tolist() if polygon_material is not None and materials else None
    current = None
    for k, poly in enumerate((np.asarray(polygons) + 1).tolist()):
        if mats is not None and mats[k] != current:
            current = mats[k]
            out.append(f"usemtl {materials[current] if 0 <= current < len(materials) else current}")
        if with_uv:
            corners = zip(poly, tex_rows[k], strict=True)
            out.append(
                "f " + " ".join(f"{i}/{t}" if t > 0 else str(i) for i, t in corners if i > 0)
            )
        else:
            out.append("f " + " ".join(str(i) for i in poly if i > 0))
    path.write_text("\n".join(out) + "\n")
