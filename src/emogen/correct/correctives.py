"""The :class:`Correctives` of a model: combinational and collision shapes plus the anchors.

Built from the model's geometry (generic neutral, deltas, topology, regions) and its rig,
deterministically, and cached beside the compiled model (``<cache_root>/correctives``), keyed
by the model hash, the rig's corrective settings, the artist files' contents and this module's
format version. A model without ICT-FaceKit's mouth regions gets no collision correctives.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from emogen.correct import collision
from emogen.correct import reach as reach_module
from emogen.correct.combinational import DerivedPair, derive_pairs, double_counted, overlap_score
from emogen.correct.lips import LIP_MESH_REGIONS, UPPER_FRONT_TEETH, mouth_geometry
from emogen.correct.reach import reach_shapes
from emogen.errors import ModelFileError
from emogen.model.io.digest import file_sha256

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

log = logging.getLogger(__name__)
FORMAT = 3  # 3: reach shapes (rig 2)
_MEMORY: dict[str, Correctives] = {}


@dataclass(frozen=True, eq=False)
class Correctives:
    """Corrective shapes of a model (arrays read-only).

    combinational_names : (C,) names; drivers : (C, K) int shape indices, driver_mask (C, K)
    combinational_deltas : (C, V, 3) float32; scores : (C,) overlap score (NaN: artist-made or
    a reach shape, :mod:`emogen.correct.reach`)
    companions : (F, 2) int, [follower, lead] shape indices
    collision_names : 8 names (or none); collision_deltas : (8, V, 3) float32
    layout : the collision anchors and lower lip (None without collision correctives)
    """

    key: str
    shape_names: tuple[str, ...]
    combinational_names: tuple[str, ...]
    drivers: np.ndarray
    driver_mask: np.ndarray
    combinational_deltas: np.ndarray
    scores: np.ndarray
    companions: np.ndarray
    collision_names: tuple[str, ...]
    collision_deltas: np.ndarray
    layout: collision.CollisionLayout | None

    @property
    def names(self) -> tuple[str, ...]:
        return self.combinational_names + self.collision_names

    @property
    def n_combinational(self) -> int:
        return len(self.combinational_names)

    @property
    def n_collision(self) -> int:
        return len(self.collision_names)

    def driver_names(self, i: int) -> tuple[str, ...]:
        return tuple(self.shape_names[d] for d in self.drivers[i][self.driver_mask[i]])

    def summary(self) -> list[dict[str, object]]:
        out: list[dict[str, object]] = []
        for i, name in enumerate(self.combinational_names):
            score = float(self.scores[i])
            out.append(
                {
                    "name": name,
                    "type": "combinational",
                    "drivers": list(self.driver_names(i)),
                    "overlap_score": None if math.isnan(score) else round(score, 3),
                }
            )
        for name in self.collision_names:
            out.append({"name": name, "type": "collision"})
        return out

    # ---- storage ---------------------------------------------------------------------------
    def arrays(self) -> dict[str, np.ndarray]:
        a: dict[str, np.ndarray] = {
            "key": np.array(self.key),
            "shape_names": np.array(self.shape_names),
            "combinational_names": np.array(self.combinational_names, dtype=str),
            "drivers": self.drivers,
            "driver_mask": self.driver_mask,
            "combinational_deltas": self.combinational_deltas,
            "scores": self.scores,
            "companions": self.companions,
            "collision_names": np.array(self.collision_names, dtype=str),
            "collision_deltas": self.collision_deltas,
        }
        if self.layout is not None:
            lay = self.layout
            a |= {
                "layout_vertices": lay.vertices,
                "layout_lower": lay.lower,
                "layout_lower_vertices": lay.lower_vertices,
                "layout_cell": np.array(lay.cell),
            }
            for k in (0, 1):
                a[f"layout_anchors{k}"] = lay.anchors[k]
                a[f"layout_anchor_bary{k}"] = lay.anchor_bary[k]
                a[f"layout_anchor_triangle{k}"] = lay.anchor_triangle[k]
        return a

    @classmethod
    def from_arrays(cls, z: dict[str, np.ndarray] | np.lib.npyio.NpzFile) -> Correctives:
        layout = None
        if "layout_vertices" in z:
            layout = collision.CollisionLayout(
                vertices=z["layout_vertices"],
                lower=z["layout_lower"],
                lower_vertices=z["layout_lower_vertices"],
                anchors=(z["layout_anchors0"], z["layout_anchors1"]),
                anchor_bary=(z["layout_anchor_bary0"], z["layout_anchor_bary1"]),
                anchor_triangle=(z["layout_anchor_triangle0"], z["layout_anchor_triangle1"]),
                cell=float(z["layout_cell"]),
            )
        return _readonly(
            cls(
                key=str(z["key"]),
                shape_names=tuple(str(s) for s in z["shape_names"]),
                combinational_names=tuple(str(s) for s in z["combinational_names"]),
                drivers=z["drivers"],
                driver_mask=z["driver_mask"],
                combinational_deltas=z["combinational_deltas"],
                scores=z["scores"],
                companions=z["companions"],
                collision_names=tuple(str(s) for s in z["collision_names"]),
                collision_deltas=z["collision_deltas"],
                layout=layout,
            )
        )


def _readonly(c: Correctives) -> Correctives:
    for value in c.arrays().values():
        if isinstance(value, np.ndarray) and value.ndim:
            value.setflags(write=False)
    return c


def _design() -> dict[str, object]:
    """The constants the collision correctives are built with (part of the cache key)."""
    return {
        name: getattr(collision, name)
        for name in (
            "LOWER_LIP_RADIUS",
            "UPPER_ANCHOR_RADIUS",
            "CROWN_FRACTION",
            "CELL_FACTOR",
            "LIP_AMPLITUDE",
            "TEETH_AMPLITUDE",
            "UPPER_FALLOFF",
            "LOWER_FALLOFF",
        )
    }


def _file_digest(path: str) -> str:
    try:
        return file_sha256(path)
    except OSError as exc:
        raise ModelFileError(f"cannot read corrective shape file {path}: {exc.strerror}") from None


def cache_key(model: FaceModel) -> str:
    settings = model.rig.corrective_settings()
    files = {c.name: _file_digest(c.file) for c in model.rig.correctives if c.file}
    text = json.dumps(
        {
            "format": FORMAT,
            "model_hash": model.model_hash,
            "rig": settings,
            "files": files,
            "design": _design(),
            # the reach shapes are code: a change to it must rebuild them
            "reach_code": file_sha256(reach_module.__file__) if model.rig.reach_version else None,
        },
        sort_keys=True,
        default=str,
    )
    return hashlib.sha256(text.encode()).hexdigest()


def _load_shape_file(model: FaceModel, name: str, path: str) -> np.ndarray:
    """An artist's corrective as offsets from the generic neutral, (V, 3) float32."""
    p = Path(path)
    if p.suffix.lower() in (".glb", ".gltf"):
        from emogen.model.io.gltf_import import import_glb

        other = import_glb(p)
        if name not in other.shape_names:
            raise ModelFileError(
                f"{p}: no morph target named '{name}' (targets: {', '.join(other.shape_names)})"
            )
        delta = other.deltas[other.shape_names.index(name)]
    else:
        from emogen.model.io.obj import parse_vertices

        delta = parse_vertices(p) - model.base_neutral
    if delta.shape != model.base_neutral.shape:
        raise ModelFileError(
            f"corrective '{name}' has {len(delta)} vertices, the model has {model.n_vertices} ({p})"
        )
    return np.asarray(delta, dtype=np.float32)


def build_correctives(model: FaceModel) -> Correctives:
    """Derive (deterministically) the correctives of ``model`` from its geometry and rig."""
    rig = model.rig
    index = {s: i for i, s in enumerate(model.shape_names)}
    names: list[str] = []
    drivers: list[tuple[str, ...]] = []
    deltas: list[np.ndarray] = []
    scores: list[float] = []
    for c in rig.correctives:
        names.append(c.name)
        drivers.append(c.drivers)
        if c.file:
            deltas.append(_load_shape_file(model, c.name, c.file))
            scores.append(math.nan)
        else:
            u, w = (model.deltas[index[d]] for d in c.drivers)
            o = double_counted(u, w)
            deltas.append((-o).astype(np.float32))
            scores.append(overlap_score(u, w, o))
    if rig.derive_min_overlap is not None:
        declared = {frozenset(d) for d in drivers}
        pairs: list[tuple[DerivedPair, np.ndarray]] = derive_pairs(
            model.deltas, model.shape_names, rig, rig.derive_min_overlap
        )
        for pair, delta in pairs:
            if frozenset(pair.drivers) in declared:
                continue
            names.append(f"corr_{pair.drivers[0]}_{pair.drivers[1]}")
            drivers.append(pair.drivers)
            deltas.append(delta)
            scores.append(pair.score)
    if rig.reach_version is not None:
        for shape in reach_shapes(model, rig.reach_version):
            names.append(shape.name)
            drivers.append(shape.drivers)
            deltas.append(shape.delta)
            scores.append(math.nan)
    k = max((len(d) for d in drivers), default=1)
    drv = np.zeros((len(names), k), dtype=np.int64)
    mask = np.zeros((len(names), k), dtype=bool)
    for i, d in enumerate(drivers):
        drv[i, : len(d)] = [index[s] for s in d]
        mask[i, : len(d)] = True
    companions = np.array(
        [[index[f], index[lead]] for f, lead in sorted(rig.companions.items())], dtype=np.int64
    ).reshape(-1, 2)

    v = model.n_vertices
    needed = (*LIP_MESH_REGIONS, *UPPER_FRONT_TEETH)
    layout = None
    col_names: tuple[str, ...] = ()
    col_deltas = np.zeros((0, v, 3), dtype=np.float32)
    if all(r in model.regions for r in needed):
        neutral = model.base_neutral.astype(np.float64)
        mouth = mouth_geometry(neutral, model.polygons, model.regions)
        layout = collision.collision_layout(
            neutral, model.faces, model.polygons, model.regions, mouth
        )
        col_names = collision.corrective_names()
        col_deltas = collision.collision_deltas(neutral, mouth)
    return _readonly(
        Correctives(
            key=cache_key(model),
            shape_names=model.shape_names,
            combinational_names=tuple(names),
            drivers=drv,
            driver_mask=mask,
            combinational_deltas=(
                np.stack(deltas) if deltas else np.zeros((0, v, 3), dtype=np.float32)
            ),
            scores=np.array(scores, dtype=np.float64),
            companions=companions,
            collision_names=col_names,
            collision_deltas=col_deltas,
            layout=layout,
        )
    )


def _cache_path(key: str) -> Path:
    from emogen.model.io.cache import cache_root

    return cache_root() / "correctives" / f"correctives-v{FORMAT}-{key[:32]}.npz"


def correctives_for(model: FaceModel, *, use_cache: bool = True) -> Correctives:
    """The model's correctives: from memory, the disk cache, or built (and then cached)."""
    key = cache_key(model)
    if use_cache and key in _MEMORY:
        return _MEMORY[key]
    path = _cache_path(key)
    found = None
    if use_cache:
        try:
            with np.load(path, allow_pickle=False) as z:
                found = Correctives.from_arrays({k: z[k] for k in z.files})
        except FileNotFoundError:
            pass
        except (OSError, ValueError, KeyError) as exc:
            log.warning("ignoring unreadable correctives cache %s: %s", path, exc)
    if found is None or found.key != key:
        found = build_correctives(model)
        if use_cache:
            from emogen.model.io.cache import _atomic_write

            try:
                arrays = found.arrays()
                _atomic_write(path, lambda fh: np.savez(fh, **arrays))  # type: ignore[arg-type]
            except OSError as exc:
                log.warning("could not write the correctives cache %s: %s", path, exc)
    if use_cache:
        _MEMORY[key] = found
    return found
