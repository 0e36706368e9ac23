"""The face model for the browser viewer: a GLB with morph targets per identity, cached on disk.

Each identity (a preset or the study's own, :func:`~emogen.appearance.identities.resolve_identity`)
gets the model with its shape, its skin textures embedded and the camera fitted to its face.
``export_model_glb`` takes a few seconds, so each (model hash, identity, textures key, package
version, GLB layout) is written once to the cache folder (beside the compiled model cache),
with a gzip copy; the textures key covers the appearance, so another appearance of the same
name never reuses a GLB.
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
from emogen.appearance.identities import Identity, resolve_identity
from emogen.errors import ConfigError
from emogen.model.face import FaceModel
from emogen.study.errors import SessionNotFound
from emogen.web.schemas import error_responses

router = APIRouter()
#: Bumped when the GLB's layout changes (2: corrective morph targets after the shapes;
#: 3: skin textures, appearance and fitted camera).
GLB_LAYOUT = 3


class ModelGLBs:
    """The viewer's GLB per identity name. ``identities``: the study's own identities
    (by name), looked up before the presets."""

    def __init__(
        self,
        model: FaceModel,
        identities: dict[str, Identity] | None = None,
        folder: Path | None = None,
    ) -> None:
        from emogen.model.io.cache import cache_root

        self.model = model
        self.identities = dict(identities or {})
        self.folder = folder or cache_root() / "glb"
        self._lock = threading.Lock()
        self._paths: dict[str, Path] = {}

    def make_all(self) -> None:
        """Every study identity's GLB made now (at the server's start), not when the first
        participant reaches that identity."""
        for identity in self.identities:
            self.path(identity)

    def path(self, identity: str) -> Path:
        """The GLB of ``identity`` (made on first use); unknown identities are not found."""
        try:
            resolved = resolve_identity(identity, self.identities)
        except ConfigError:
            raise SessionNotFound(f"no identity '{identity}' in this study") from None
        from emogen.appearance.textures import skin_textures
        from emogen.render.look import default_look, fitted_look

        with self._lock:
            known = self._paths.get(identity)
            if known is not None and known.is_file() and known.with_suffix(".glb.gz").is_file():
                return known
            model = self.model.with_identity(resolved.shape)
            look = default_look()
            textures = skin_textures(model, resolved.appearance, irradiance=look.front_irradiance())
            name = (
                f"{self.model.model_hash[:20]}-{identity}-{textures.key[:16]}-{__version__}"
                f"-l{GLB_LAYOUT}.glb"
            )
            path = self.folder / name
            if not path.is_file() or not path.with_suffix(".glb.gz").is_file():
                from emogen.render.model_glb import export_model_glb

                self.folder.mkdir(parents=True, exist_ok=True)
                camera = fitted_look(look, model, resolved.appearance).camera
                tmp = path.with_suffix(f".tmp{os.getpid()}.glb")
                export_model_glb(model, tmp, textures=textures, camera=camera)
                data = tmp.read_bytes()
                gz = path.with_suffix(f".tmp{os.getpid()}.gz")
                gz.write_bytes(gzip.compress(data, compresslevel=6, mtime=0))
                os.replace(gz, path.with_suffix(".glb.gz"))
                os.replace(tmp, path)
            self._paths[identity] = path
        return path


@router.get(
    "/api/model/{identity}.glb",
    responses={200: {"content": {"model/gltf-binary": {}}}, **error_responses(404, 422, 503)},
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
