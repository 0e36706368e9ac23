"""Loading a face model: an ICT-FaceKit folder (through the array cache) or a GLB."""

from __future__ import annotations

import os
from pathlib import Path

from emogen.model.face import FaceModel, IdentityLike, from_arrays

__all__ = ["PACKAGED_RIGS", "load_model", "model_for_recorded_hash", "records_of"]


def load_model(
    path: str | os.PathLike[str] | None = None,
    identity: IdentityLike = None,
    *,
    rig: str | os.PathLike[str] | None = None,
    use_cache: bool = True,
) -> FaceModel:
    """Load a face model: an ICT-FaceKit ``FaceXModel`` folder or an ARKit-named GLB.

    ``path`` None looks in ``$EMOGEN_MODEL``, then the user cache (``emogen model fetch``).
    ``identity``: None (generic neutral), a preset name (``male``, ``female``) or coefficients.
    ``rig``: a rig TOML; the packaged ICT rig by default.
    """
    from emogen.model.io import cache
    from emogen.model.io.ict import load_ict_folder
    from emogen.model.locate import find_model
    from emogen.model.rig_build import load_rig

    where = find_model(path)
    rig_path = Path(rig) if rig is not None else None
    if where.suffix.lower() in (".glb", ".gltf"):
        from emogen.model.io.gltf_import import import_glb

        model = import_glb(where, rig=rig_path)
    else:
        arrays = cache.load_cached(where) if use_cache else None
        if arrays is None:
            arrays = load_ict_folder(where)
            if use_cache:
                cache.store(where, arrays)
        model = from_arrays(arrays, load_rig(arrays.shape_names, rig_path), source=str(where))
    return model if identity is None else model.with_identity(identity)


#: the packaged ICT rigs, newest first (docs/model.md, "Rig versions"): rig 2 adds the reach
#: shapes and the revised anger block, rig 3 the open smile, anger's lip tightener and fear's
#: parted lips; rigs 1 and 2 are kept so that studies recorded with them replay and continue
#: exactly as they were recorded.
PACKAGED_RIGS = (
    ("ict-rig-3", "ict_rig.toml"),
    ("ict-rig-2", "ict_rig_2.toml"),
    ("ict-rig-1", "ict_rig_1.toml"),
)


def records_of(model: FaceModel, recorded_hash: str) -> bool:
    """Whether a record with ``recorded_hash`` was made with ``model``: its hash, or its
    version-1 hash (records made before hash version 2) when its rig has no reach shapes — the
    rigs of that time had none (:mod:`emogen.model.model_hash`)."""
    if recorded_hash == model.model_hash:
        return True
    return recorded_hash == model.legacy_model_hash and model.rig.reach_version is None


def model_for_recorded_hash(model: FaceModel, recorded_hash: str) -> FaceModel:
    """``model`` with the packaged rig a record was made with: the model itself when it made
    the record (:func:`records_of`), else the same model files with the packaged rig
    (:data:`PACKAGED_RIGS`) that did; ``model`` itself when none did (the caller then reports
    the mismatch). Identity: the generic one, as studies load it."""
    if records_of(model, recorded_hash) or not model.source:
        return model
    from importlib import resources

    for _name, file in PACKAGED_RIGS:
        with resources.as_file(resources.files("emogen.data").joinpath(file)) as rig_path:
            other = load_model(model.source, rig=rig_path)
        if records_of(other, recorded_hash):
            return other
    return model
