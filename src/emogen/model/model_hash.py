"""The model hash recorded with every output: everything that shapes a stimulus.

Version 2 (``MODEL_HASH_VERSION``) covers the geometry (name, shape list, neutral, deltas), the
topology (polygons, UVs, per-polygon UV indices and materials), the identity modes, the
landmarks, the regions and the rig (genes, exclusions, eye shapes, gaze, emotion blocks,
identity presets, correctives — with the SHA-256 of each corrective's file, not its path —
derived-corrective settings and companions). The appearance is painted procedurally from these
and from its own parameters, which every record stores beside the hash with the appearance
generator's version.

Version 1 (:func:`emogen.model.io.ict.model_content_hash`) covered the geometry only: a neutral
mesh cut inside its face lines kept its hash. Records made before version 2 carry a version-1
hash; :func:`emogen.study.context.accepted_hashes` accepts it as an alias of the same model,
so studies recorded then still replay (tests/data/study_stream1.sqlite).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from emogen.errors import ModelFileError
from emogen.model.io.digest import file_sha256

if TYPE_CHECKING:
    from emogen.model.io.ict import ModelArrays
    from emogen.model.regions import Region
    from emogen.model.rig import Rig

__all__ = ["MODEL_HASH_VERSION", "rig_description", "stimulus_hash"]

MODEL_HASH_VERSION = 2


def _file_digest(path: str) -> str:
    try:
        return file_sha256(path)
    except OSError as exc:
        raise ModelFileError(f"cannot read corrective shape file {path}: {exc.strerror}") from None


def rig_description(rig: Rig) -> dict[str, object]:
    """Everything of a rig that changes a face or the GA's genes (JSON-ready, canonical).

    The reach version is described only when the rig declares one, so a rig without it (rig 1,
    ``ict_rig_1.toml``) keeps the hash its studies recorded."""
    gaze = rig.gaze
    reach = {} if rig.reach_version is None else {"reach": rig.reach_version}
    return reach | {
        "name": rig.name,
        "shapes": list(rig.shape_names),
        "genes": [[g.name, list(g.shapes), g.eye] for g in rig.genes],
        "excluded": sorted(rig.excluded),
        "emotions": {
            k: [e.action_units, list(e.core), list(e.optional)]
            for k, e in sorted(rig.emotions.items())
        },
        "identities": {k: list(v.coefficients) for k, v in sorted(rig.identities.items())},
        "gaze": None
        if gaze is None
        else {
            "eyeballs": [gaze.left_eyeball, gaze.right_eyeball],
            "look": [
                np.asarray(a).tolist()
                for a in (gaze.look_left, gaze.look_right, gaze.look_up, gaze.look_down)
            ],
            "angles": [gaze.yaw, gaze.pitch_up, gaze.pitch_down],
        },
        "correctives": [
            [c.name, list(c.drivers), _file_digest(c.file) if c.file else None]
            for c in rig.correctives
        ],
        "derive_min_overlap": rig.derive_min_overlap,
        "companions": dict(sorted(rig.companions.items())),
    }


def stimulus_hash(arrays: ModelArrays, rig: Rig, regions: Mapping[str, Region]) -> str:
    """Hex SHA-256 (version 2) of a model's arrays, its regions and its rig."""
    h = hashlib.sha256(f"emogen-model-hash-v{MODEL_HASH_VERSION}\n".encode())
    h.update(f"{arrays.model_hash}\n".encode())  # name, shapes, neutral, deltas (version 1)
    topo = arrays.topology
    for name, array in (
        ("polygons", topo.polygons),
        ("polygon_uvs", topo.polygon_uvs),
        ("uvs", topo.uvs),
        ("polygon_material", topo.polygon_material),
        ("identity_deltas", arrays.identity_deltas),
        ("landmarks", arrays.landmarks),
    ):
        a = np.ascontiguousarray(array)
        h.update(f"{name} {a.dtype.str} {a.shape}\n".encode())
        h.update(a.tobytes())
    text = {
        "materials": list(topo.materials),
        "identities": list(arrays.identity_names),
        "regions": {
            k: [r.v_start, r.v_stop, r.p_start, r.p_stop, r.group]
            for k, r in sorted(regions.items())
        },
        "rig": rig_description(rig),
    }
    h.update(json.dumps(text, sort_keys=True).encode())
    return h.hexdigest()
