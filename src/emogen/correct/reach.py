"""Reach shapes: derived combinational correctives that let the rig reach FACS apex actions.

ICT-FaceKit's shapes stop short of several actions the emotion prototypes need (measured in
``benchmarks/bench_reach.py``, docs/model.md "Reach"): ``browDown`` (AU4) lowers the inner brow
by 2 mm and knits it by 4 mm, no shape bulges the skin under the lower lid in a smile (AU6
with AU12), the nasolabial fold stays shallow, ``eyeSquint`` (AU7) barely raises the lower lid,
``mouthStretch`` (AU20) pulls the corners back more than sideways, and AU1 with AU4 (the brows
of fear and sadness) cancel where FACS has them raised *and* drawn together.

Each reach shape is built here from the model's own geometry — its driver shapes' offsets and
smooth fields placed by the 68 landmarks on the generic neutral — never sculpted by hand, and
is activated like every combinational corrective, by the product of its drivers' weights
(paper Section III-A): zero when any driver is zero. A left shape uses left landmarks and left
drivers, its right twin the mirrored ones; the neutral is left/right symmetric, so the twins
mirror each other (tested against the mesh's mirror map). All lengths are centimetres, model
axes: x to the subject's left, y up, z forward.

Version 1 (``[reach] version = 1`` in the rig; rig 2, ``ict_rig_2.toml``):

==========================  ========================  =============================================
name (per side)             drivers                   offsets
==========================  ========================  =============================================
``reach_browDown``          browDown                  0.8 × browDown (lowers the brow further),
                                                      knit: inner brow 0.6 mm more towards the
                                                      midline
                                                      (0 at the midline), glabellar bulge 1.2 mm
``reach_browRaiseKnit``     browInnerUp × browDown    undoes 1.4 × browDown's lowering (y, z),
                                                      keeps its knitting: AU1+4 raised and knit
``reach_duchenne``          cheekSquint × mouthSmile  0.5 × cheekSquint (cheek raise), a bulge of
                                                      1.4 mm under the lower lid (the orbicularis
                                                      pad of a Duchenne smile)
``reach_nasolabial``        mouthSmile                the cheek lateral to the nasolabial line
                                                      pushed 3 mm forward over a 1 mm
                                                      crease along the line: a fold
``reach_lidTighten``        eyeSquint                 0.6 × eyeSquint (AU7: lower lid raised,
                                                      tightened)
``reach_lipStretch``        mouthStretch              0.6 × mouthStretch's sideways offset, 0.2 ×
                                                      its vertical, 0.3 × its backward (AU20)
==========================  ========================  =============================================

Version 2 (rig 3, ``ict_rig.toml``): version 1 and four more, for the mouths the emotion
prototypes lacked (FACS AU12 at E with AU25: the upper lip drawn up off the upper teeth; AU23:
the lips narrowed and their red thinned):

==========================  ========================  =============================================
``reach_smileOpen``         mouthSmile ×              0.4 × (mouthUpperUp − mouthLowerDown): the
                            mouthLowerDown            lips part by raising the upper lip as well
                                                      as lowering the lower, showing upper teeth
``reach_lipTightener``      mouthPress                0.5 × (mouthRollUpper + mouthRollLower),
                                                      each unpaired shape made mirror-symmetric
                                                      and split into sides that sum to the whole
``reach_tightenRolled*``    mouthPress ×              −0.5 × that roll's side (``…Upper``,
                            mouthRollUpper or         ``…Lower``): a lip the face already rolls
                            mouthRollLower            is not rolled past ICT's full roll
==========================  ========================  =============================================
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import cKDTree

from emogen.errors import ModelFileError

if TYPE_CHECKING:
    from emogen.model.face import FaceModel

#: Multi-PIE 68-point landmarks per side (+1: the subject's left, x > 0; -1: right): the inner
#: brow, the lower lid (two points), the nose's ala and the mouth corner.
BROW_INNER = {+1: 22, -1: 21}
LID_LOWER = {+1: (46, 47), -1: (41, 40)}
ALA = {+1: 35, -1: 31}
CORNER = {+1: 54, -1: 48}
SIDE = {+1: "_L", -1: "_R"}
MIRROR = np.array([-1.0, 1.0, 1.0])
REACH_VERSIONS = (1, 2)
REACH_PREFIX = "reach_"  # every reach shape's name starts so
#: reach shapes that only cap a roll (rarely on, no relief of their own): the viewer's GLB
#: gives them no normal deltas, as other correctives (it keeps the GLB within 3 MB on the wire)
NO_RELIEF = ("reach_tightenRolled",)


@dataclass(frozen=True)
class ReachShape:
    """One derived shape: name, driver shape names, offsets (V, 3) float32 (cm)."""

    name: str
    drivers: tuple[str, ...]
    delta: np.ndarray


def falloff(r: np.ndarray) -> np.ndarray:
    """(1 − r²)² inside r < 1, 0 outside: smooth (C¹) at the border."""
    inside = np.clip(1.0 - np.asarray(r, dtype=np.float64) ** 2, 0.0, None)
    return inside * inside


def smoothstep(a: float, b: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((np.asarray(x, dtype=np.float64) - a) / (b - a), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def ellipse(p: np.ndarray, centre: tuple[float, float], radii: tuple[float, float]) -> np.ndarray:
    """Normalised distance of points p (V, 3) from ``centre`` in the x–y (frontal) plane."""
    return np.hypot((p[:, 0] - centre[0]) / radii[0], (p[:, 1] - centre[1]) / radii[1])


class _Builder:
    """The generic neutral, the face mask and the driver offsets a reach shape is built from."""

    def __init__(self, model: FaceModel) -> None:
        if "face" not in model.regions or len(model.landmarks) < 68:
            raise ModelFileError(
                "reach shapes need ICT-FaceKit's 'face' region and its 68 landmarks; "
                f"model '{model.name}' has {len(model.landmarks)} landmarks"
            )
        self.neutral = model.base_neutral.astype(np.float64)
        face = model.regions["face"]
        self.face = np.zeros(len(self.neutral), dtype=bool)
        self.face[face.v_start : face.v_stop] = True
        self.landmarks = model.landmarks
        self.shapes = {s: i for i, s in enumerate(model.shape_names)}
        self.deltas = model.deltas
        # the mesh's mirror map: the vertex at each vertex's reflection (x → −x), where one is
        dist, self.mirror = cKDTree(self.neutral).query(self.neutral * MIRROR)
        self.mirrored = dist < 1e-4

    def point(self, index: int) -> np.ndarray:
        return self.neutral[self.landmarks[index]]

    def delta(self, shape: str) -> np.ndarray:
        if shape not in self.shapes:
            raise ModelFileError(f"reach shapes need the shape '{shape}'; the model has none")
        return self.deltas[self.shapes[shape]].astype(np.float64)

    def symmetric(self, shape: str, s: int) -> np.ndarray:
        """Side ``s`` of a left/right shape pair, averaged with its twin's mirror image: ICT's
        twins differ by up to 0.8 mm, the reach shapes of the two sides mirror exactly."""
        own, twin = self.delta(shape + SIDE[s]), self.delta(shape + SIDE[-s])
        mean = (own + twin[self.mirror] * MIRROR) / 2
        return np.where(self.mirrored[:, None], mean, own)

    def side_of(self, shape: str, s: int) -> np.ndarray:
        """Side ``s`` of an unpaired (whole-mouth) shape: made mirror-symmetric, then weighted
        across the midline so that the two sides' halves sum to the whole shape."""
        own = self.delta(shape)
        mean = (own + own[self.mirror] * MIRROR) / 2
        whole = np.where(self.mirrored[:, None], mean, own)
        return whole * smoothstep(-0.3, 0.3, s * self.neutral[:, 0])[:, None]

    def field(self, values: np.ndarray) -> np.ndarray:
        """Offsets (V, 3) confined to the face mesh (not the eyes, teeth or head)."""
        return np.where(self.face[:, None], values, 0.0)


def _brow_down(b: _Builder, s: int) -> np.ndarray:
    p = b.neutral
    inner = b.point(BROW_INNER[s])
    own = 0.8 * b.symmetric("browDown", s)
    # knit: the inner brow and the glabella beside it slide towards the midline, not across it
    toward_midline = smoothstep(0.0, 1.0, s * p[:, 0])
    knit = falloff(ellipse(p, (inner[0], inner[1] - 0.2), (2.2, 1.5))) * toward_midline
    # glabellar bulge between brows and nasion, each side's half blending into the other's
    half = smoothstep(-0.3, 0.3, s * p[:, 0])
    bulge = falloff(ellipse(p, (s * 0.45, inner[1] - 0.85), (0.9, 1.0))) * half
    extra = np.zeros_like(p)
    extra[:, 0] = -s * 0.06 * knit
    extra[:, 1] = 0.03 * bulge
    extra[:, 2] = 0.12 * bulge
    return own + b.field(extra)


def _brow_raise_knit(b: _Builder, s: int) -> np.ndarray:
    down = b.symmetric("browDown", s)
    out = np.zeros_like(down)
    out[:, 1:] = -1.4 * down[:, 1:]
    return out


def _duchenne(b: _Builder, s: int) -> np.ndarray:
    p = b.neutral
    lid = np.mean([b.point(i) for i in LID_LOWER[s]], axis=0)
    pad = falloff(ellipse(p, (lid[0], lid[1] - 0.48), (1.25, 0.33)))
    bulge = np.zeros_like(p)
    bulge[:, 1] = 0.04 * pad
    bulge[:, 2] = 0.14 * pad
    return 0.5 * b.symmetric("cheekSquint", s) + b.field(bulge)


def _nasolabial(b: _Builder, s: int) -> np.ndarray:
    p = b.neutral
    ala, corner = b.point(ALA[s]), b.point(CORNER[s])
    start = ala[:2] + np.array([s * 0.45, 0.45])  # the alar crease, above and beside the ala
    end = corner[:2] + np.array([s * 0.75, -0.85])  # beside and below the mouth corner
    axis = (end - start) / np.linalg.norm(end - start)
    length = float(np.linalg.norm(end - start))
    rel = p[:, :2] - start
    t = rel @ axis / length  # 0 at the crease, 1 below the corner
    perp = np.array([axis[1], -axis[0]])
    perp = perp if s * perp[0] > 0 else -perp  # away from the midline, into the cheek
    lateral = rel @ perp
    along = smoothstep(-0.15, 0.12, t) * (1.0 - smoothstep(0.8, 1.15, t))
    front = smoothstep(corner[2] - 3.0, corner[2] - 2.0, p[:, 2])  # not the side of the head
    cheek = smoothstep(-0.05, 0.35, lateral) * (1.0 - smoothstep(0.8, 2.2, lateral))
    crease = falloff(np.abs(lateral) / 0.35)
    fold = np.zeros_like(p)
    fold[:, 2] = (0.30 * cheek - 0.10 * crease) * along * front
    fold[:, 1] = 0.05 * cheek * along * front
    return b.field(fold)


def _lid_tighten(b: _Builder, s: int) -> np.ndarray:
    return 0.6 * b.symmetric("eyeSquint", s)


def _lip_stretch(b: _Builder, s: int) -> np.ndarray:
    return b.symmetric("mouthStretch", s) * np.array([0.6, 0.2, 0.3])


def _smile_open(b: _Builder, s: int) -> np.ndarray:
    return 0.4 * (b.symmetric("mouthUpperUp", s) - b.symmetric("mouthLowerDown", s))


def _lip_tightener(b: _Builder, s: int) -> np.ndarray:
    return 0.5 * (b.side_of("mouthRollUpper", s) + b.side_of("mouthRollLower", s))


def _unroll(shape: str) -> Callable[[_Builder, int], np.ndarray]:
    """−0.5 × side of a lip roll: with the tightener's +0.5 × press, the roll a face gets is
    roll + 0.5 press (1 − roll) ≤ 1, never beyond the roll ICT's shape was made for."""
    return lambda b, s: -0.5 * b.side_of(shape, s)


#: version 1: (name, drivers without side, builder(builder, side))
VERSION_1: tuple[tuple[str, tuple[str, ...], Callable[[_Builder, int], np.ndarray]], ...] = (
    ("reach_browDown", ("browDown",), _brow_down),
    ("reach_browRaiseKnit", ("browInnerUp", "browDown"), _brow_raise_knit),
    ("reach_duchenne", ("cheekSquint", "mouthSmile"), _duchenne),
    ("reach_nasolabial", ("mouthSmile",), _nasolabial),
    ("reach_lidTighten", ("eyeSquint",), _lid_tighten),
    ("reach_lipStretch", ("mouthStretch",), _lip_stretch),
)


#: version 2 (rig 3): version 1, the open smile, the lip tightener and its cap on rolled lips
VERSION_2 = (
    *VERSION_1,
    ("reach_smileOpen", ("mouthSmile", "mouthLowerDown"), _smile_open),
    ("reach_lipTightener", ("mouthPress",), _lip_tightener),
    ("reach_tightenRolledUpper", ("mouthPress", "mouthRollUpper"), _unroll("mouthRollUpper")),
    ("reach_tightenRolledLower", ("mouthPress", "mouthRollLower"), _unroll("mouthRollLower")),
)
VERSIONS = {1: VERSION_1, 2: VERSION_2}


def reach_shapes(model: FaceModel, version: int) -> list[ReachShape]:
    """The reach shapes of ``version`` for ``model``, left then right for each (docstring)."""
    if version not in REACH_VERSIONS:
        raise ModelFileError(f"reach version must be one of {REACH_VERSIONS}; got {version}")
    b = _Builder(model)
    out = []
    for name, drivers, build in VERSIONS[version]:
        for s in (+1, -1):
            out.append(
                ReachShape(
                    name=name + SIDE[s],
                    drivers=tuple(d + SIDE[s] if d + SIDE[s] in b.shapes else d for d in drivers),
                    delta=build(b, s).astype(np.float32),
                )
            )
    return out
