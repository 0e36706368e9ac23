"""Loading a face model: an ICT-FaceKit folder (through the array cache) or a GLB."""

from __future__ import annotations

import os
from pathlib import Path

from emogen.model.face import FaceModel, IdentityLike, from_arrays

__all__ = ["load_model"]


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
