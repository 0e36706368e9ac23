"""The face model for the browser viewer: a GLB with morph targets per identity, cached on disk.

``export_model_glb`` takes a few seconds, so each (model hash, identity, package version, GLB
layout) is written once to the cache folder (beside the compiled model cache), with a gzip copy.
"""

from __future__ import annotations

import gzip
import os
import threading
from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, Request
from fastapi import Path as PathParam
from fastapi.responses import FileResponse

from emogen import __version__
from emogen.model.face import FaceModel
from emogen.study.errors import SessionNotFound

router = APIRouter()
#: Bumped when the GLB's layout changes (2: corrective morph targets after the shapes).
GLB_LAYOUT = 2


class ModelGLBs:
    def __init__(self, model: FaceModel, folder: Path | None = None) -> None:
        from emogen.model.io.cache import cache_root

        self.model = model
        self.folder = folder or cache_root() / "glb"
        self._lock = threading.Lock()

    def path(self, identity: str) -> Path:
        """The GLB of ``identity`` (made on first use); unknown identities are not found."""
        if identity != "generic" and identity not in self.model.rig.identities:
            raise SessionNotFound(f"no identity '{identity}' in this study's model")
        name = f"{self.model.model_hash[:20]}-{identity}-{__version__}-l{GLB_LAYOUT}.glb"
        path = self.folder / name
        with self._lock:
            if not path.is_file() or not path.with_suffix(".glb.gz").is_file():
                from emogen.model.io.gltf import export_model_glb

                self.folder.mkdir(parents=True, exist_ok=True)
                model = self.model if identity == "generic" else self.model.with_identity(identity)
                tmp = path.with_suffix(f".tmp{os.getpid()}.glb")
                export_model_glb(model, tmp)
                data = tmp.read_bytes()
                gz = path.with_suffix(f".tmp{os.getpid()}.gz")
                gz.write_bytes(gzip.compress(data, compresslevel=6, mtime=0))
                os.replace(gz, path.with_suffix(".glb.gz"))
                os.replace(tmp, path)
        return path


@router.get(
    "/api/model/{identity}.glb",
    responses={200: {"content": {"model/gltf-binary": {}}}},
    response_class=FileResponse,
)
def model_glb(
    request: Request,
    identity: Annotated[str, PathParam(pattern=r"^[A-Za-z0-9_-]{1,64}$")],
) -> FileResponse:
    """The face model (morph targets in the model's shape order) for the 3D viewer."""
    path = request.app.state.glbs.path(identity)
    headers = {"Cache-Control": "public, max-age=86400"}
    if "gzip" in request.headers.get("accept-encoding", ""):
        headers["Content-Encoding"] = "gzip"
        headers["Vary"] = "Accept-Encoding"
        return FileResponse(
            path.with_suffix(".glb.gz"), media_type="model/gltf-binary", headers=headers
        )
    return FileResponse(path, media_type="model/gltf-binary", headers=headers)
