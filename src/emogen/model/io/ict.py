"""Reading an ICT-FaceKit ``FaceXModel`` folder into arrays.

The folder holds the neutral (``generic_neutral_mesh.obj``), one OBJ per expression shape
(the 53 named in ``vertex_indices.json`` plus ``cheekRaiser_L/R`` and ``PupilDilate_L/R``) and
identity modes ``identityNNN.obj``. Every OBJ shares the neutral's vertex order; only the
neutral's topology is read.
"""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from emogen.errors import ModelFileError
from emogen.model.io.obj import ObjTopology, parse_topology, parse_vertices, read_bytes

NEUTRAL_FILE = "generic_neutral_mesh.obj"
INDEX_FILE = "vertex_indices.json"
EXTRA_SHAPES = ("cheekRaiser_L", "cheekRaiser_R", "PupilDilate_L", "PupilDilate_R")
IDENTITY_PATTERN = re.compile(r"^identity(\d{3})\.obj$")


@dataclass(frozen=True)
class ModelArrays:
    """Everything a face model is made of, as plain arrays (what the cache stores)."""

    name: str
    neutral: np.ndarray  # (V, 3) float32
    shape_names: tuple[str, ...]
    deltas: np.ndarray  # (S, V, 3) float32: shape - neutral
    identity_names: tuple[str, ...]
    identity_deltas: np.ndarray  # (I, V, 3) float32: identity mode - neutral
    topology: ObjTopology
    source_hash: str  # sha256 of the source files' bytes
    model_hash: str  # sha256 of name, shape list, vertex count and the float32 arrays
    #: (68,) int32 vertex ids of the 68-point facial landmarks (jaw 0-16, brows 17-26, nose
    #: 27-35, eyes 36-47, lips 48-67) from ``vertex_indices.json``; empty when unknown
    landmarks: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))


def expected_shapes(folder: Path) -> tuple[str, ...]:
    """The expression shapes a FaceXModel folder must have, from its ``vertex_indices.json``."""
    index = folder / INDEX_FILE
    try:
        data = json.loads(read_bytes(index))
        names = data["expressions"]
    except json.JSONDecodeError as exc:
        raise ModelFileError(f"{index}: not valid JSON ({exc.msg} at line {exc.lineno})") from None
    except (KeyError, TypeError):
        raise ModelFileError(f"{index}: has no 'expressions' list of shape names") from None
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise ModelFileError(f"{index}: 'expressions' must be a list of shape names")
    return tuple(names) + EXTRA_SHAPES


def landmark_vertices(folder: Path, n_vertices: int) -> np.ndarray:
    """The 68 landmark vertex ids of ``vertex_indices.json`` (empty if it lists none)."""
    index = folder / INDEX_FILE
    data = json.loads(read_bytes(index))
    ids = data.get("idx_to_landmark_verts") if isinstance(data, dict) else None
    if ids is None:
        return np.zeros(0, dtype=np.int32)
    arr = np.asarray(ids)
    if arr.shape != (68,) or arr.dtype.kind not in "iu" or arr.min() < 0 or arr.max() >= n_vertices:
        raise ModelFileError(
            f"{index}: 'idx_to_landmark_verts' must be 68 vertex ids in [0, {n_vertices}); "
            f"got shape {arr.shape}"
        )
    return arr.astype(np.int32)


def source_files(folder: Path) -> tuple[list[str], list[str]]:
    """(expression shape names, identity file stems) present and required in ``folder``.

    Raises ModelFileError for a missing folder, a missing neutral or shape, or an OBJ file
    that is neither a known shape nor an identity mode.
    """
    if not folder.is_dir():
        raise ModelFileError(f"model folder does not exist: {folder}")
    shapes = list(expected_shapes(folder))
    present = {p.name for p in folder.iterdir() if p.suffix.lower() == ".obj"}
    if NEUTRAL_FILE not in present:
        raise ModelFileError(f"the neutral mesh is missing: {folder / NEUTRAL_FILE}")
    missing = [s for s in shapes if f"{s}.obj" not in present]
    if missing:
        raise ModelFileError(
            f"{len(missing)} expression shape file(s) missing from {folder}: "
            + ", ".join(f"{s}.obj" for s in missing)
        )
    identities = sorted(p[:-4] for p in present if IDENTITY_PATTERN.match(p))
    known = {NEUTRAL_FILE, *(f"{s}.obj" for s in shapes), *(f"{i}.obj" for i in identities)}
    extra = sorted(present - known)
    if extra:
        raise ModelFileError(
            f"unexpected OBJ file(s) in {folder}: {', '.join(extra)}; expected only the neutral, "
            f"the {len(shapes)} expression shapes of {INDEX_FILE} plus {', '.join(EXTRA_SHAPES[:2])}"
            f"/{', '.join(EXTRA_SHAPES[2:])}, and identityNNN.obj modes"
        )
    return shapes, identities


def model_content_hash(
    name: str, shape_names: tuple[str, ...], neutral: np.ndarray, deltas: np.ndarray
) -> str:
    """The model hash recorded with every output: name, shape list, vertex count, geometry."""
    h = hashlib.sha256()
    h.update(f"{name}\n{len(neutral)}\n{','.join(shape_names)}\n".encode())
    h.update(np.ascontiguousarray(neutral, dtype=np.float32).tobytes())
    h.update(np.ascontiguousarray(deltas, dtype=np.float32).tobytes())
    return h.hexdigest()


#: Vertices of ICT-FaceKit's FaceXModel: a folder with this many is checked against the pinned
#: manifest (``emogen/data/ict_manifest.json``) file by file.
ICT_VERTICES = 26719
ALLOW_MODIFIED_ENV = "EMOGEN_ALLOW_MODIFIED_MODEL"


def check_pinned(folder: Path, digests: dict[str, tuple[int, str]]) -> None:
    """Compare an ICT-FaceKit folder's files with the pinned manifest; name every difference.

    digests : file name → (size, sha256) of the files read. A difference is an error unless
    ``$EMOGEN_ALLOW_MODIFIED_MODEL`` is set (a model changed on purpose: its hash differs from
    the pinned model's, so records tell the two apart).
    """
    import os

    from emogen.model.io.manifest import load_manifest

    manifest = load_manifest()
    pinned = {Path(f.path).name: f for f in manifest.files if f.path.startswith("FaceXModel/")}
    differ = []
    for file_name, (size, sha) in sorted(digests.items()):
        entry = pinned.get(file_name)
        if entry is None or entry.sha256 == sha:
            continue
        what = f"{size} bytes, pinned {entry.size}" if size != entry.size else "content differs"
        differ.append(f"{file_name} ({what})")
    if differ and not os.environ.get(ALLOW_MODIFIED_ENV):
        raise ModelFileError(
            f"{folder} differs from the pinned ICT-FaceKit files (commit {manifest.commit[:8]}) "
            f"in {len(differ)} file(s): {', '.join(differ[:5])}{' …' if len(differ) > 5 else ''}"
            f"; a cut or partial download? Run `emogen model fetch` for the pinned files, or set "
            f"{ALLOW_MODIFIED_ENV}=1 for a model you changed on purpose"
        )


def load_ict_folder(folder: Path, name: str = "ict-facekit") -> ModelArrays:
    """Parse every OBJ of an ICT-FaceKit folder (the slow path the cache avoids); a folder of
    ICT-FaceKit's size is checked against the pinned manifest (:func:`check_pinned`)."""
    shapes, identities = source_files(folder)
    src = hashlib.sha256()
    digests: dict[str, tuple[int, str]] = {}

    def read(stem: str) -> tuple[Path, bytes]:
        path = folder / f"{stem}.obj"
        text = read_bytes(path)
        src.update(path.name.encode() + b"\0" + text)
        digests[path.name] = (len(text), hashlib.sha256(text).hexdigest())
        return path, text

    neutral_path, neutral_text = read(NEUTRAL_FILE[:-4])
    neutral = parse_vertices(neutral_path, neutral_text)
    n_vertices = len(neutral)
    topology = parse_topology(neutral_path, n_vertices, neutral_text)

    def deltas_of(stems: list[str]) -> np.ndarray:
        out = np.empty((len(stems), n_vertices, 3), dtype=np.float32)
        for k, stem in enumerate(stems):
            path, text = read(stem)
            verts = parse_vertices(path, text)
            if len(verts) != n_vertices:
                raise ModelFileError(
                    f"shape '{stem}' has {len(verts)} vertices, neutral has {n_vertices} ({path})"
                )
            out[k] = verts - neutral
        return out

    deltas = deltas_of(shapes)
    identity_deltas = deltas_of(identities)
    if n_vertices == ICT_VERTICES:
        index = read_bytes(folder / INDEX_FILE)
        digests[INDEX_FILE] = (len(index), hashlib.sha256(index).hexdigest())
        check_pinned(folder, digests)
    neutral32 = neutral.astype(np.float32)
    return ModelArrays(
        name=name,
        neutral=neutral32,
        shape_names=tuple(shapes),
        deltas=deltas,
        identity_names=tuple(identities),
        identity_deltas=identity_deltas,
        topology=topology,
        source_hash=src.hexdigest(),
        model_hash=model_content_hash(name, tuple(shapes), neutral32, deltas),
        landmarks=landmark_vertices(folder, n_vertices),
    )
