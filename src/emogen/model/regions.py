"""Named sub-mesh regions: contiguous vertex and polygon ranges of a face model.

The ICT-FaceKit ranges below are facts from the ICT-FaceKit README (inclusive ranges there,
stored here as half-open ``[start, stop)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Region:
    """A named part of the mesh: vertices ``[v_start, v_stop)``, polygons ``[p_start, p_stop)``."""

    name: str
    v_start: int
    v_stop: int
    p_start: int
    p_stop: int
    group: str = "part"

    @property
    def vertices(self) -> slice:
        return slice(self.v_start, self.v_stop)

    @property
    def polygons(self) -> slice:
        return slice(self.p_start, self.p_stop)

    @property
    def n_vertices(self) -> int:
        return self.v_stop - self.v_start

    def vertex_indices(self) -> np.ndarray:
        return np.arange(self.v_start, self.v_stop)


def _r(name: str, v: tuple[int, int], p: tuple[int, int], group: str = "part") -> Region:
    # README ranges are inclusive at both ends.
    return Region(name, v[0], v[1] + 1, p[0], p[1] + 1, group)


_ICT_PARTS = [
    _r("face", (0, 9408), (0, 9229)),
    _r("head_neck", (9409, 11247), (9230, 11143)),
    _r("mouth_socket", (11248, 13293), (11144, 13225)),
    _r("eye_socket_left", (13294, 13677), (13226, 13629)),
    _r("eye_socket_right", (13678, 14061), (13630, 14033)),
    _r("gums_tongue", (14062, 17038), (14034, 17005)),
    _r("teeth", (17039, 21450), (17006, 21495)),
    _r("eyeball_left", (21451, 23020), (21496, 23093)),
    _r("eyeball_right", (23021, 24590), (23094, 24691)),
    _r("lacrimal_left", (24591, 24794), (24692, 24854)),
    _r("lacrimal_right", (24795, 24998), (24855, 25017)),
    _r("eye_blend_left", (24999, 25022), (25018, 25032)),
    _r("eye_blend_right", (25023, 25046), (25033, 25047)),
    _r("eye_occlusion_left", (25047, 25198), (25048, 25175)),
    _r("eye_occlusion_right", (25199, 25350), (25176, 25303)),
    _r("eyelashes_left", (25351, 26034), (25304, 25843)),
    _r("eyelashes_right", (26035, 26718), (25844, 26383)),
]

_ICT_DETAIL = [
    _r("narrow_face", (0, 6705), (0, 6559), "face_area"),
    _r("sclera_left", (21451, 22220), (21496, 22295), "eyeball"),
    _r("iris_left", (22221, 23020), (22296, 23093), "eyeball"),
    _r("sclera_right", (23021, 23790), (23094, 23893), "eyeball"),
    _r("iris_right", (23791, 24590), (23894, 24691), "eyeball"),
]

# (name, inclusive vertex range, inclusive polygon range), in the README's order.
_ICT_TEETH = [
    ("upper_left_molar_3", (17039, 17229), (17006, 17203)),
    ("upper_left_molar_2", (17230, 17415), (17204, 17397)),
    ("upper_left_molar_1", (17416, 17606), (17398, 17592)),
    ("upper_left_bicuspid_2", (17607, 17729), (17593, 17717)),
    ("upper_left_bicuspid_1", (17730, 17894), (17718, 17885)),
    ("upper_left_canine", (17895, 17990), (17886, 17979)),
    ("upper_left_incisor_lateral", (17991, 18066), (17980, 18053)),
    ("upper_left_incisor_central", (18067, 18142), (18054, 18127)),
    ("upper_right_incisor_central", (18143, 18218), (18128, 18201)),
    ("upper_right_incisor_lateral", (18219, 18294), (18202, 18275)),
    ("upper_right_canine", (18295, 18390), (18276, 18369)),
    ("upper_right_bicuspid_1", (18391, 18555), (18370, 18537)),
    ("upper_right_bicuspid_2", (18556, 18678), (18538, 18662)),
    ("upper_right_molar_1", (18679, 18869), (18663, 18857)),
    ("upper_right_molar_2", (18870, 19055), (18858, 19051)),
    ("upper_right_molar_3", (19056, 19246), (19052, 19249)),
    ("lower_left_molar_3", (19247, 19425), (19250, 19433)),
    ("lower_left_molar_2", (19426, 19601), (19434, 19615)),
    ("lower_left_molar_1", (19602, 19813), (19616, 19831)),
    ("lower_left_bicuspid_2", (19814, 19951), (19832, 19972)),
    ("lower_left_bicuspid_1", (19952, 20078), (19973, 20103)),
    ("lower_left_canine", (20079, 20168), (20104, 20193)),
    ("lower_left_incisor_lateral", (20169, 20262), (20194, 20288)),
    ("lower_left_incisor_central", (20263, 20348), (20289, 20372)),
    ("lower_right_incisor_central", (20349, 20434), (20373, 20456)),
    ("lower_right_incisor_lateral", (20435, 20528), (20457, 20551)),
    ("lower_right_canine", (20529, 20618), (20552, 20641)),
    ("lower_right_bicuspid_1", (20619, 20745), (20642, 20772)),
    ("lower_right_bicuspid_2", (20746, 20883), (20773, 20913)),
    ("lower_right_molar_1", (20884, 21095), (20914, 21129)),
    ("lower_right_molar_2", (21096, 21271), (21130, 21311)),
    ("lower_right_molar_3", (21272, 21450), (21312, 21495)),
]

ICT_N_VERTICES = 26719
ICT_N_POLYGONS = 26384


def ict_regions() -> dict[str, Region]:
    """Every named ICT-FaceKit region: sub-meshes, face areas, eyeball parts and each tooth."""
    regions = {r.name: r for r in (*_ICT_PARTS, *_ICT_DETAIL)}
    for name, v, p in _ICT_TEETH:
        regions[f"tooth_{name}"] = _r(f"tooth_{name}", v, p, "tooth")
    return regions


# Parts a viewer shows; the rest (eye blend/occlusion, lacrimal fluid) are shading helpers
# meant for a real-time engine's special shaders.
ICT_VISIBLE_PARTS = (
    "face",
    "head_neck",
    "mouth_socket",
    "eye_socket_left",
    "eye_socket_right",
    "gums_tongue",
    "teeth",
    "eyeball_left",
    "eyeball_right",
    "eyelashes_left",
    "eyelashes_right",
)
