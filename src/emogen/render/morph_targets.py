"""The morph-target arrays of the viewer's model GLB: targets, thinning, quantization.

One target per shape (in the model's order), then one per corrective (combinational then
collision). Positions and position deltas are int16 (KHR_mesh_quantization; the node's scale
and translation undo it), normals int8; without quantization float32 in metres. Corrective
targets leave out vertices moved less than a tolerance and round their deltas to about that
step; by default they carry no normal deltas (zero): with their own normals the ICT GLB grows
past 3 MB gzipped (3.03 MB even with a 4.5/127 normal tolerance), without them it is 2.85 MB.
The reach shapes (:mod:`emogen.correct.reach`: folds, bulges, furrows, seen by their shading)
keep their normal deltas, thinned by that tolerance, but for the caps on rolled lips
(``NO_RELIEF``).
A corrected face is then within this tolerance per unit corrective weight.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from emogen.correct.faces import model_correctives
from emogen.correct.reach import NO_RELIEF, REACH_PREFIX
from emogen.model.geometry import vertex_normals
from emogen.model.io.gltf_asset import CM_TO_M

if TYPE_CHECKING:
    from emogen.correct.correctives import Correctives
    from emogen.model.face import FaceModel

CORRECTIVE_TOLERANCE_CM = 0.01
CORRECTIVE_NORMAL_TOLERANCE = 4.5 / 127
_Q16 = 32767  # int16 normalized: value = q / 32767
_Q8 = 127  # int8 normalized
_FLOAT_TOLERANCE = 1e-4  # cm (and unit-normal components): float targets leave out smaller


@dataclass(frozen=True)
class MorphTargets:
    """Exact targets over the exported vertices U (float64, centimetres).

    neutral : (U, 3); shapes : (S + C, U, 3) every target's face; deltas : (S + C, U, 3)
    position deltas (correctives thinned); normals0 : (U, 3) the neutral's unit normals;
    normal_deltas : (S + C, U, 3); the first ``n_shapes`` targets are shapes.
    """

    neutral: np.ndarray
    shapes: np.ndarray
    deltas: np.ndarray
    normals0: np.ndarray
    normal_deltas: np.ndarray
    n_shapes: int
    corrective_names: tuple[str, ...]

    @property
    def n_targets(self) -> int:
        return len(self.deltas)


@dataclass(frozen=True)
class EncodedTargets:
    """What the GLB stores: base and target attributes, and the faces they decode to (cm)."""

    pos_base: np.ndarray
    pos_delta: np.ndarray
    nrm_base: np.ndarray
    nrm_delta: np.ndarray
    base_cm: np.ndarray
    delta_cm: np.ndarray
    step: float  # quantization step, cm (0 when float)
    clamped: int  # normal-delta components clamped to int8's [-1, 1]
    node: dict[str, Any]  # the node's translation and scale that undo the quantization


def morph_targets(
    model: FaceModel,
    vertices: np.ndarray,
    triangles: np.ndarray,
    *,
    correctives: bool,
    corrective_tolerance_cm: float,
    corrective_normal_tolerance: float,
    corrective_normals: bool,
) -> MorphTargets:
    """The targets of ``model`` over the exported ``vertices`` (U,) (``triangles`` over them)."""
    neutral = model.neutral[vertices].astype(np.float64)
    target_deltas = model.deltas[:, vertices].astype(np.float64)
    corrective_names: tuple[str, ...] = ()
    if correctives and model.n_shapes:
        c = model_correctives(model)
        corrective_names = tuple(c.names)
        if corrective_names:
            target_deltas = np.concatenate(
                [
                    target_deltas,
                    c.combinational_deltas[:, vertices].astype(np.float64),
                    c.collision_deltas[:, vertices].astype(np.float64),
                ]
            )
    shapes = neutral[None] + target_deltas  # (S + C, U, 3)
    normals0 = vertex_normals(neutral, triangles)
    delta = shapes - neutral[None]
    dn = vertex_normals(shapes, triangles) - normals0[None]
    if corrective_names:
        # Corrective targets are sparser than the shapes (to keep the GLB small on the wire):
        # vertices a corrective moves less than the tolerance are left out of its target.
        cd, cn = delta[model.n_shapes :], dn[model.n_shapes :]
        cd[np.linalg.norm(cd, axis=-1) < corrective_tolerance_cm] = 0.0
        # the reach shapes are relief (a fold, a bulge, furrows), seen by their shading: they
        # keep their normal deltas, thinned like the others' (+0.01 MB on the wire)
        keep = np.array([corrective_normals or _relief(n) for n in corrective_names])
        cn[~keep] = 0.0
        _exact_at_apex(model_correctives(model), neutral, triangles, normals0, delta, dn)
        cn[np.abs(cn).max(axis=-1) < corrective_normal_tolerance] = 0.0
    return MorphTargets(neutral, shapes, delta, normals0, dn, model.n_shapes, corrective_names)


def _relief(name: str) -> bool:
    """A reach shape whose target keeps its normal deltas (not the lips' :data:`NO_RELIEF`)."""
    return name.startswith(REACH_PREFIX) and not name.startswith(NO_RELIEF)


def _exact_at_apex(
    c: Correctives,
    neutral: np.ndarray,
    triangles: np.ndarray,
    normals0: np.ndarray,
    delta: np.ndarray,
    dn: np.ndarray,
) -> None:
    """Give each reach shape the normal delta that makes the viewer's blend of normals exact
    where its drivers and it are at 1 (in place on ``dn``, the targets' normal deltas).

    The viewer blends normals linearly (the neutral's plus Σ w·Δn); the offscreen renderer
    recomputes them from the blended mesh. Where several large targets meet on little skin (fear:
    inner and outer brow raise, brow lowering and the AU1+4 knit on the upper lid) the linear
    blend tilted the lid fold's normals into a dark crease band, 0.93/255 off the offscreen
    face; with this, 0.69/255 (docs/render.md). As a combinational corrective fixes its drivers' positions, its
    normal delta now fixes their normals: Δn_c = n(neutral + Σ drivers' δ + Σ the correctives
    of those drivers' δ) − n₀ − Σ their Δn.
    """
    s = len(c.shape_names)
    drivers = [frozenset(c.drivers[i][c.driver_mask[i]].tolist()) for i in range(len(c.drivers))]
    reach = [i for i, n in enumerate(c.combinational_names) if _relief(n)]
    for i in sorted(reach, key=lambda i: len(drivers[i])):  # a reach shape's sub-blends first
        # the driver shapes, and every combinational corrective they switch fully on (itself too)
        on = [*sorted(drivers[i]), *(s + j for j, d in enumerate(drivers) if d <= drivers[i])]
        others = [k for k in on if k != s + i]
        apex = neutral + delta[on].sum(axis=0)
        dn[s + i] = vertex_normals(apex, triangles) - normals0 - dn[others].sum(axis=0)


def quantized(t: MorphTargets, corrective_tolerance_cm: float) -> EncodedTargets:
    """int16 positions and deltas, int8 normals, centred and scaled by the node."""
    lo, hi = t.neutral.min(0), t.neutral.max(0)
    centre = (lo + hi) / 2
    half = float(max((hi - lo).max() / 2, np.abs(t.deltas).max(initial=0.0), 1e-6))
    step = half / _Q16
    q0 = np.clip(np.rint((t.neutral - centre) / step), -_Q16, _Q16)
    # Deltas rounded on their own (not as differences of rounded shapes): a face's error
    # is then e0 + Σ w_k e_k with independent e_k, not amplified by Σ w_k.
    qd = np.rint(t.deltas / step)
    if t.corrective_names:  # coarser steps (multiples of step): fewer distinct bytes to gzip
        f = max(1.0, float(np.floor(corrective_tolerance_cm / step)))
        qd[t.n_shapes :] = np.rint(t.deltas[t.n_shapes :] / (f * step)) * f
    qd = np.clip(qd, -_Q16, _Q16)
    n0 = np.rint(t.normals0 * _Q8)
    dn = np.rint(t.normal_deltas * _Q8)
    return EncodedTargets(
        pos_base=q0.astype(np.int16),
        pos_delta=qd.astype(np.int16),
        nrm_base=n0.astype(np.int8),
        nrm_delta=np.clip(dn, -_Q8, _Q8).astype(np.int8),
        base_cm=centre + q0 * step,
        delta_cm=qd * step,
        step=step,
        clamped=int(np.count_nonzero(np.abs(dn) > _Q8)),
        node={"translation": [float(x) * CM_TO_M for x in centre], "scale": [half * CM_TO_M] * 3},
    )


def float32(t: MorphTargets) -> EncodedTargets:
    """float32 positions and deltas in metres; changes under 1e-4 left out of the targets."""
    delta, dn = t.deltas, t.normal_deltas
    delta[np.all(np.abs(delta) < _FLOAT_TOLERANCE, axis=-1)] = 0.0
    dn[np.all(np.abs(dn) < _FLOAT_TOLERANCE, axis=-1)] = 0.0
    pos_base = (t.neutral * CM_TO_M).astype(np.float32)
    pos_delta = (delta * CM_TO_M).astype(np.float32)
    return EncodedTargets(
        pos_base=pos_base,
        pos_delta=pos_delta,
        nrm_base=t.normals0.astype(np.float32),
        nrm_delta=dn.astype(np.float32),
        base_cm=pos_base / CM_TO_M,
        delta_cm=pos_delta / CM_TO_M,
        step=0.0,
        clamped=0,
        node={},
    )


def max_errors(t: MorphTargets, enc: EncodedTargets) -> tuple[float, float]:
    """Largest decoded-vs-exact distance (cm): over the neutral and the shapes, and over the
    correctives (tolerance included)."""
    u = len(t.neutral)
    faces_cm = enc.base_cm[None] + np.concatenate([np.zeros((1, u, 3)), enc.delta_cm])
    exact = np.concatenate([t.neutral[None], t.shapes])
    errors = np.linalg.norm(faces_cm - exact, axis=-1)
    return float(errors[: t.n_shapes + 1].max()), float(errors[t.n_shapes + 1 :].max(initial=0.0))
