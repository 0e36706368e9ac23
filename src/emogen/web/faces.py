"""Server-side face images (PNG) for browsers without WebGL, rendered by ``emogen.render``.

OpenGL contexts belong to the thread that made them, so every render runs on one worker thread
that owns one renderer per identity: the identity's shape with its appearance (skin tone, brows,
lips, hair), as in the browser viewer. Recent images are cached by (identity, weights). With
``correct`` (the study's ``correct = true``) the faces are corrected as in the GA and the
browser viewer (``Renderer.render(weights, correct=True)``) from their shape weights. Each image
has the study's framing (``oval``: seen through look.json's oval on the background, as the
viewer's tiles are). A face that moves comes as frames (one row of weights each: the task's
``face``); its image is the strip of those frames left to right, each corrected on its own.
"""

from __future__ import annotations

import asyncio
import hashlib
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from emogen.appearance.identities import Identity, resolve_identity
from emogen.model.face import FaceModel

PNG_SIZE = 256
CACHE_SIZE = 512


class FacePNGs:
    """PNGs of faces by identity name.

    identities : the study's identities by name (``StudyConfig.study_identities()``); names not
        in it are looked up among the presets (``emogen.appearance.identities.PRESETS``)
    framing : the study's framing (``face`` or ``oval``, :mod:`emogen.study.framing`)
    """

    def __init__(
        self,
        model: FaceModel,
        size: int = PNG_SIZE,
        *,
        correct: bool = True,
        identities: dict[str, Identity] | None = None,
        framing: str = "face",
    ) -> None:
        self.model = model
        self.size = size
        self.correct = correct
        self.identities = dict(identities or {})
        self.framing = framing
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="emogen-render")
        self._renderers: dict[str, Any] = {}
        self._cache: OrderedDict[str, bytes] = OrderedDict()

    async def render(self, weights: np.ndarray, identity: str) -> bytes:
        """The PNG of one face (weights (n,)) or a strip of frames (weights (frames, n))."""
        w = np.asarray(weights, dtype=np.float64)[..., : self.model.n_shapes]
        key = f"{identity}:{w.shape}:" + hashlib.sha256(w.tobytes()).hexdigest()
        if key in self._cache:
            self._cache.move_to_end(key)
            return self._cache[key]
        loop = asyncio.get_running_loop()
        png = await loop.run_in_executor(self._pool, self._render, w, identity)
        self._cache[key] = png
        while len(self._cache) > CACHE_SIZE:
            self._cache.popitem(last=False)
        return png

    def _render(self, weights: np.ndarray, identity: str) -> bytes:
        from emogen.render.images import png_bytes
        from emogen.render.renderer import Renderer

        if identity not in self._renderers:
            ident = resolve_identity(identity, self.identities)
            model = self.model.with_identity(ident.shape)
            self._renderers[identity] = Renderer(
                model, size=self.size, appearance=ident.appearance, framing=self.framing
            )
        frames = self._renderers[identity].render(np.atleast_2d(weights), correct=self.correct)
        return png_bytes(np.concatenate(list(frames), axis=1))  # a strip when there are frames

    def close(self) -> None:
        def release() -> None:
            for r in self._renderers.values():
                r.close()
            self._renderers.clear()

        self._pool.submit(release).result()
        self._pool.shutdown()
