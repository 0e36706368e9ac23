"""FaceModel: a blendshape face, F = B0 + Σ_k α_k (B_k − B0), evaluated in batches.

Identities shift the neutral, B0(β) = N + Σ_i β_i (I_i − N); expression deltas are applied on
top unchanged. Arrays are read-only; a model with another identity shares the deltas.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from emogen.errors import ConfigError, ShapeError
from emogen.model.geometry import sphere_fit
from emogen.model.io.ict import ModelArrays
from emogen.model.io.obj import ObjTopology, triangulate
from emogen.model.model_hash import stimulus_hash
from emogen.model.regions import Region, ict_regions
from emogen.model.rig import Rig

# Faces evaluated per matrix product: bounds the working memory beyond the output
# (one chunk of float32 vertices is CHUNK × V × 12 bytes, 80 MB for ICT at 256).
DEFAULT_CHUNK = 256

IdentityLike = str | np.ndarray | list[float] | tuple[float, ...] | None


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class FaceModel:
    """A blendshape face model.

    neutral : (V, 3) float32, the identity's neutral B0
    deltas : (S, V, 3) float32, B_k − N for each expression shape, in ``shape_names`` order
    polygons : (P, 4) int32, quads and triangles (-1 pads a triangle's 4th corner)
    faces : (T, 3) int32, the polygons split into triangles
    """

    name: str
    neutral: np.ndarray
    deltas: np.ndarray
    shape_names: tuple[str, ...]
    polygons: np.ndarray
    uvs: np.ndarray
    polygon_uvs: np.ndarray
    polygon_material: np.ndarray
    materials: tuple[str, ...]
    regions: dict[str, Region]
    rig: Rig
    model_hash: str
    base_neutral: np.ndarray  # N, the mean identity
    identity_names: tuple[str, ...] = ()
    identity_deltas: np.ndarray | None = None  # (I, V, 3)
    identity: np.ndarray = field(default_factory=lambda: np.zeros(0))
    identity_label: str = "generic"
    source: str = ""
    #: (68,) int32 landmark vertex ids (ICT's ``vertex_indices.json``), empty when unknown
    landmarks: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    #: the version-1 hash (geometry only) that studies recorded before version 2 carry; read
    #: by :func:`emogen.study.context.accepted_hashes` only (needed by
    #: tests/study/test_recorded_before.py::test_recorded_study_replays_exactly)
    legacy_model_hash: str = ""

    def hash_matches(self, recorded: str) -> bool:
        """Whether a record's model hash is this model's (version 2, see
        :mod:`emogen.model.model_hash`)."""
        return bool(recorded) and recorded == self.model_hash

    # ---- sizes --------------------------------------------------------------------------
    @property
    def n_vertices(self) -> int:
        return int(self.neutral.shape[0])

    @property
    def n_shapes(self) -> int:
        return len(self.shape_names)

    @property
    def n_identity_modes(self) -> int:
        return 0 if self.identity_deltas is None else int(self.identity_deltas.shape[0])

    @cached_property
    def faces(self) -> np.ndarray:
        tris, _ = triangulate(self.polygons)
        return _readonly(tris)

    @cached_property
    def _blend_matrix(self) -> np.ndarray:
        """(S + 1, V·3): the deltas with the neutral as a last row, so one product blends."""
        return _readonly(
            np.vstack([self.deltas.reshape(self.n_shapes, -1), self.neutral.reshape(1, -1)])
        )

    def shape_index(self, name: str) -> int:
        try:
            return self.shape_names.index(name)
        except ValueError:
            raise ShapeError(
                f"unknown shape '{name}'; this model's shapes are: {', '.join(self.shape_names)}"
            ) from None

    # ---- evaluation ---------------------------------------------------------------------
    def check_weights(self, weights: np.ndarray, dtype: type = np.float32) -> np.ndarray:
        """``weights`` as a contiguous (n_faces, n_shapes) array of ``dtype``; ShapeError if not."""
        w: np.ndarray = np.asarray(weights, dtype=dtype)
        if w.ndim == 1:
            raise ShapeError(
                f"weights must be 2-D (n_faces, {self.n_shapes}); got 1-D shape {w.shape}: "
                "pass one face as weights[None, :]"
            )
        if w.ndim != 2 or w.shape[1] != self.n_shapes:
            raise ShapeError(f"weights must have shape (n_faces, {self.n_shapes}); got {w.shape}")
        if not np.all(np.isfinite(w)):
            raise ShapeError("weights contain NaN or infinity")
        return np.ascontiguousarray(w)

    def evaluate(
        self,
        weights: np.ndarray,
        *,
        gaze: bool = True,
        out: np.ndarray | None = None,
        chunk: int = DEFAULT_CHUNK,
    ) -> np.ndarray:
        """Vertices of faces: weights (n_faces, n_shapes) → (n_faces, n_vertices, 3) float32.

        The blend is one matrix product per chunk of faces, written straight into ``out``
        (allocated when None; pass a memory map to stream huge batches to disk). Beyond the
        output, working memory is bounded by ``chunk``. With ``gaze`` and a rig that declares
        it, the eyeballs rotate rigidly with the ``eyeLook*`` weights. Corrected faces:
        :func:`emogen.correct.evaluate_corrected`.
        """
        w = self.check_weights(weights)
        n = w.shape[0]
        if out is None:
            out = np.empty((n, self.n_vertices, 3), dtype=np.float32)
        elif out.shape != (n, self.n_vertices, 3) or out.dtype != np.float32:
            raise ShapeError(
                f"out must be float32 of shape {(n, self.n_vertices, 3)}; got {out.dtype} {out.shape}"
            )
        for start, stop in _chunks(n, chunk):
            self._evaluate_into(w[start:stop], out[start:stop], gaze)
        return out

    def evaluate_chunks(
        self, weights: np.ndarray, *, gaze: bool = True, chunk: int = DEFAULT_CHUNK
    ) -> Iterator[tuple[slice, np.ndarray]]:
        """Stream faces in chunks: yields (slice of the batch, vertices of those faces).

        The yielded buffer is reused between chunks; copy what you keep.
        """
        w = self.check_weights(weights)
        buf = np.empty((min(chunk, max(len(w), 1)), self.n_vertices, 3), dtype=np.float32)
        for start, stop in _chunks(len(w), chunk):
            view = buf[: stop - start]
            self._evaluate_into(w[start:stop], view, gaze)
            yield slice(start, stop), view

    def _evaluate_into(self, w: np.ndarray, out: np.ndarray, gaze: bool) -> None:
        w1 = np.empty((len(w), self.n_shapes + 1), dtype=np.float32)
        w1[:, :-1] = w
        w1[:, -1] = 1.0
        np.matmul(w1, self._blend_matrix, out=out.reshape(len(w), -1))
        if gaze and self.rig.gaze is not None:
            self._rotate_eyes(w, out)

    @cached_property
    def _eye_pivots(self) -> list[tuple[slice, np.ndarray]]:
        gz = self.rig.gaze
        if gz is None:
            return []
        pivots = []
        for name in (gz.left_eyeball, gz.right_eyeball):
            if name not in self.regions:
                raise ConfigError(f"rig gaze names region '{name}', which this model does not have")
            sl = self.regions[name].vertices
            pivots.append((sl, sphere_fit(self.neutral[sl])[0]))
        return pivots

    def _rotate_eyes(self, w: np.ndarray, out: np.ndarray) -> None:
        gz = self.rig.gaze
        if gz is None:
            return
        yaw, pitch = gz.angles(w.astype(np.float64))
        moving = np.flatnonzero((yaw != 0) | (pitch != 0))
        if len(moving) == 0:
            return
        # Row vectors: p' = (p − c) Rᵀ + c = p Rᵀ + (c − c Rᵀ), one batched product per eye.
        rot = gaze_rotations(yaw[moving], pitch[moving])
        rot_t = rot.transpose(0, 2, 1)
        rot_t32 = np.ascontiguousarray(rot_t, dtype=np.float32)
        every = len(moving) == len(w)
        for sl, centre in self._eye_pivots:
            shift = (centre - centre @ rot_t).astype(np.float32)[:, None, :]
            if every:
                eye = out[:, sl]
                rotated = np.matmul(eye, rot_t32)
                rotated += shift
                eye[...] = rotated
            else:
                rotated = np.matmul(out[moving, sl], rot_t32)
                rotated += shift
                out[moving, sl] = rotated

    # ---- identities ---------------------------------------------------------------------
    def with_identity(self, identity: IdentityLike) -> FaceModel:
        """The same model with another identity: a preset name, coefficients, or None (generic)."""
        beta, label = self.resolve_identity(identity)
        if self.identity_deltas is None or len(beta) == 0:
            neutral = self.base_neutral
        else:
            flat = beta.astype(np.float32) @ self.identity_deltas.reshape(len(beta), -1)
            neutral = (self.base_neutral.reshape(-1) + flat).reshape(self.base_neutral.shape)
        return replace(
            self,
            neutral=_readonly(neutral.astype(np.float32)),
            identity=_readonly(beta),
            identity_label=label,
        )

    def resolve_identity(self, identity: IdentityLike) -> tuple[np.ndarray, str]:
        k = self.n_identity_modes
        if identity is None or (isinstance(identity, str) and identity == "generic"):
            return np.zeros(k), "generic"
        if isinstance(identity, str):
            presets = self.rig.identities
            if identity not in presets:
                raise ConfigError(
                    f"unknown identity '{identity}'; presets are: generic, {', '.join(sorted(presets))}"
                )
            coeffs = np.asarray(presets[identity].coefficients, dtype=np.float64)
            label = identity
        else:
            coeffs = np.asarray(identity, dtype=np.float64).reshape(-1)
            label = "custom"
        if len(coeffs) > k:
            raise ConfigError(
                f"identity has {len(coeffs)} coefficients; this model has {k} identity modes"
            )
        if not np.all(np.isfinite(coeffs)):
            raise ConfigError("identity coefficients contain NaN or infinity")
        return np.pad(coeffs, (0, k - len(coeffs))), label

    def sample_identity(self, *, rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
        """Random identity coefficients β ~ N(0, scale²) per mode (ICT modes are unit-variance)."""
        return rng.normal(0.0, scale, size=self.n_identity_modes)

    # ---- summaries ----------------------------------------------------------------------
    def info(self) -> dict[str, object]:
        return {
            "name": self.name,
            "source": self.source,
            "model_hash": self.model_hash,
            "model_hash_v1": self.legacy_model_hash,
            "n_vertices": self.n_vertices,
            "n_polygons": len(self.polygons),
            "n_triangles": len(self.faces),
            "n_shapes": self.n_shapes,
            "shapes": list(self.shape_names),
            "identity": {"label": self.identity_label, "modes": self.n_identity_modes},
            "regions": {
                r.name: {
                    "vertices": [r.v_start, r.v_stop],
                    "polygons": [r.p_start, r.p_stop],
                    "group": r.group,
                }
                for r in self.regions.values()
            },
            "rig": self.rig.summary(),
        }


def _chunks(n: int, chunk: int) -> Iterator[tuple[int, int]]:
    if chunk < 1:
        raise ConfigError(f"chunk must be at least 1; got {chunk}")
    for start in range(0, n, chunk):
        yield start, min(start + chunk, n)


def gaze_rotations(yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations turning the +z gaze axis by ``yaw`` toward +x then ``pitch`` toward +y."""
    cy, sy = np.cos(yaw), np.sin(yaw)
    cp, sp = np.cos(pitch), np.sin(pitch)
    z, o = np.zeros_like(yaw), np.ones_like(yaw)
    ry = np.stack(
        [np.stack([cy, z, sy], -1), np.stack([z, o, z], -1), np.stack([-sy, z, cy], -1)], -2
    )
    rx = np.stack(
        [np.stack([o, z, z], -1), np.stack([z, cp, sp], -1), np.stack([z, -sp, cp], -1)], -2
    )
    return ry @ rx


def from_arrays(
    arrays: ModelArrays, rig: Rig, regions: dict[str, Region] | None = None, source: str = ""
) -> FaceModel:
    """Build a FaceModel from :class:`~emogen.model.io.ict.ModelArrays`."""
    topo: ObjTopology = arrays.topology
    n_vertices = len(arrays.neutral)
    if regions is None:
        regions = (
            ict_regions()
            if n_vertices == 26719
            else {"all": Region("all", 0, n_vertices, 0, len(topo.polygons))}
        )
    ident = arrays.identity_deltas if len(arrays.identity_names) else None
    return FaceModel(
        name=arrays.name,
        neutral=_readonly(arrays.neutral),
        base_neutral=_readonly(arrays.neutral),
        deltas=_readonly(arrays.deltas),
        shape_names=tuple(arrays.shape_names),
        polygons=_readonly(topo.polygons),
        uvs=_readonly(topo.uvs),
        polygon_uvs=_readonly(topo.polygon_uvs),
        polygon_material=_readonly(topo.polygon_material),
        materials=topo.materials,
        regions=regions,
        rig=rig,
        model_hash=stimulus_hash(arrays, rig, regions),
        legacy_model_hash=arrays.model_hash,
        identity_names=tuple(arrays.identity_names),
        identity_deltas=None if ident is None else _readonly(ident),
        identity=np.zeros(0 if ident is None else len(ident)),
        source=source,
        landmarks=_readonly(np.asarray(arrays.landmarks, dtype=np.int32)),
    )
