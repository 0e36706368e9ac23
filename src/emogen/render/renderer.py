"""Offscreen face rendering: weights (n_faces, n_shapes) → sRGB images (n_faces, size, size, 3).

    from emogen.render import Renderer
    with Renderer(model, size=512) as r:
        images = r.render(weights)          # (n_faces, 512, 512, 3) uint8

One OpenGL context per :class:`Renderer`; faces are evaluated in one batch (``FaceModel.evaluate``)
and drawn one after another into the same framebuffer.
"""

from __future__ import annotations

from functools import cache
from types import TracebackType
from typing import Any, Self

import numpy as np

from emogen.appearance.long_hair import apply_layer
from emogen.appearance.params import Appearance
from emogen.appearance.textures import SkinTextures, skin_textures
from emogen.correct.faces import correct_faces, corrected_vertices, model_correctives
from emogen.errors import ShapeError
from emogen.model.face import FaceModel
from emogen.render.gl import GLRenderer
from emogen.render.images import apply_oval, contact_sheet
from emogen.render.look import Look, default_look, fitted_look
from emogen.render.scene import FaceMesh, face_mesh
from emogen.render.wrinkles import TargetStrains, skin_strain_operator


@cache
def _blas() -> Any:
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


class Renderer:
    """Renders faces of ``model`` offscreen with the look of ``look.json``.

    appearance : the skin's look (:class:`~emogen.appearance.Appearance`: tone, brows, lips,
        hair, stubble), painted once into a texture and cached; None draws flat part colours
        (also for models without ICT's landmarks and UV layout)
    framing : ``face`` (default: hairline to chin fills ≥ 80% of the height), ``oval`` (the
        face framing through an oval: hair, ears and neck hidden) or ``head`` (head and
        shoulders), from ``look.json``
    size : image side in pixels (default ``look.size_px``, 512)
    supersample : anti-aliasing factor (default ``look.supersample``, 2: 4 samples a pixel; 1: none)
    background : sRGB triple in [0, 1]; fov_y_deg : vertical field of view in degrees
    """

    def __init__(
        self,
        model: FaceModel,
        *,
        size: int | None = None,
        look: Look | None = None,
        supersample: int | None = None,
        background: tuple[float, float, float] | None = None,
        fov_y_deg: float | None = None,
        appearance: Appearance | None = None,
        framing: str | None = None,
    ) -> None:
        base = look or default_look()
        self.look = base.with_options(background=background, fov_y_deg=fov_y_deg, framing=framing)
        if fov_y_deg is None:
            self.look = fitted_look(self.look, model, appearance)
        self.model = model
        self.mesh: FaceMesh = face_mesh(model, self.look)
        self.size = int(size or self.look.size_px)
        self._gl = GLRenderer(
            self.mesh,
            self.look,
            self.size,
            self.look.supersample if supersample is None else supersample,
        )
        self.appearance = appearance
        self.textures: SkinTextures | None = None
        self.strain: TargetStrains | None = None
        if appearance is not None:
            op = skin_strain_operator(model, self.mesh, self.look)
            self.strain = TargetStrains(op, len(self.mesh.source), self._target_delta)
            self.textures = skin_textures(
                model, appearance, irradiance=self.look.front_irradiance()
            )
            self._gl.set_textures(self.textures.albedo, self.textures.detail)
            self._gl.set_wrinkle_strength(appearance.wrinkle_strength)
        self.hair_layer = self._hair_layer()

    def _hair_layer(self) -> np.ndarray | None:
        """The long-hair layer of this identity at this size (``hair = "long"`` under the
        ``face`` framing, or ``oval``'s, which shows it through the oval), decoded from the
        bytes the viewer's GLB carries; None for other appearances, framings and models
        without landmarks."""
        a = self.appearance
        if a is None or a.hair != "long" or self.look.framing not in self.look.fits:
            return None
        if len(self.model.landmarks) != 68:
            return None
        from emogen.appearance.long_hair import (
            decode_layer,
            identity_layer,
            layer_webp,
            resample_layer,
        )

        layer = identity_layer(self.model, a, self.look.camera)
        return resample_layer(decode_layer(layer_webp(layer)), self.size)

    def _target_delta(self, k: int) -> np.ndarray:
        """Morph target ``k``'s displacement at the drawn vertices: the shapes, then the
        correctives (combinational, then collision), as in the viewer's GLB."""
        src = self.mesh.source
        if k < self.model.n_shapes:
            return self.model.deltas[k][src]
        c = model_correctives(self.model)
        deltas = np.concatenate([c.combinational_deltas, c.collision_deltas])
        return deltas[k - self.model.n_shapes][src]

    # ---- context manager ---------------------------------------------------------------
    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        self._gl.release()

    # ---- rendering ---------------------------------------------------------------------
    def render(
        self, weights: np.ndarray, *, gaze: bool = True, correct: bool = False
    ) -> np.ndarray:
        """Faces of ``weights (n_faces, n_shapes)`` → ``(n_faces, size, size, 3) uint8`` sRGB.

        correct : apply the model's correctives first
        (:func:`~emogen.correct.faces.evaluate_corrected`: combinational and lip/teeth
        collision correctives). The browser viewer's GLB holds the
        corrective targets too, so given the full vector (shapes then corrective weights) it
        draws the corrected face.
        """
        # BLAS on one thread: a few faces gain nothing from more, and OpenBLAS's idle threads
        # spin on the cores that llvmpipe then rasterises with (measured: ~15 ms a 512² face).
        with _blas().limit(limits=1, user_api="blas"):
            w = np.asarray(weights, dtype=np.float32)
            if correct:
                result = correct_faces(self.model, w)
                vertices = corrected_vertices(self.model, result, gaze=gaze)
                targets = np.concatenate([result.weights, result.correctives], axis=1)
            else:
                vertices = self.model.evaluate(w, gaze=gaze)
                targets = self.model.check_weights(w, np.float32)
        return self.render_vertices(vertices, targets=targets)

    def render_vertices(
        self,
        vertices: np.ndarray,
        *,
        albedo: np.ndarray | None = None,
        targets: np.ndarray | None = None,
    ) -> np.ndarray:
        """Meshes ``(n_faces, n_vertices, 3)`` in cm (the model's topology) → images.

        albedo : optional per-vertex linear RGB ``(n_vertices, 3)`` or ``(n_faces, n_vertices, 3)``
        replacing the look's part colours (error heatmaps).
        targets : the faces' morph-target weights ``(n_faces, K)`` (shapes, then correctives) whose
        per-target skin strains make the wrinkles (:class:`~emogen.render.wrinkles.TargetStrains`);
        None: no wrinkles.
        """
        v = np.asarray(vertices, dtype=np.float32)
        if v.ndim != 3 or v.shape[1:] != (self.mesh.n_vertices, 3):
            raise ShapeError(
                f"vertices must have shape (n_faces, {self.mesh.n_vertices}, 3); got {v.shape}"
            )
        if albedo is not None:
            albedo = np.asarray(albedo, dtype=np.float32)
            if albedo.shape not in ((self.mesh.n_vertices, 3), (len(v), self.mesh.n_vertices, 3)):
                raise ShapeError(
                    f"albedo must have shape ({self.mesh.n_vertices}, 3) or "
                    f"({len(v)}, {self.mesh.n_vertices}, 3); got {albedo.shape}"
                )
        out = np.empty((len(v), self.size, self.size, 3), dtype=np.uint8)
        normals = self.mesh.normals(v)
        try:
            for i in range(len(v)):
                if albedo is not None:
                    self._gl.set_albedo(albedo if albedo.ndim == 2 else albedo[i])
                strain = None
                if self.strain is not None and albedo is None and targets is not None:
                    strain = self.strain.face(targets[i])
                out[i] = self._gl.draw(v[i], normals[i], strain)
        finally:
            if albedo is not None:
                self._gl.set_albedo(None)
        if self.hair_layer is not None and albedo is None:
            out = apply_layer(out, self.hair_layer)
        if self.look.oval is not None:
            out = apply_oval(out, self.look.oval, self.look.background_srgb)
        return out

    def sheet(
        self,
        weights: np.ndarray,
        labels: list[str] | None = None,
        *,
        columns: int = 5,
        footer: str | None = None,
        gaze: bool = True,
        correct: bool = False,
    ) -> np.ndarray:
        """A contact sheet of the faces of ``weights (n_faces, n_shapes)``: (H, W, 3) uint8.

        Labels go under the faces; footer None writes the ICT-FaceKit notice, "" none.
        """
        return contact_sheet(
            self.render(weights, gaze=gaze, correct=correct),
            labels,
            columns=columns,
            footer=footer,
            background=self.look.background_srgb,
        )


def render_faces(model: FaceModel, weights: np.ndarray, **options: object) -> np.ndarray:
    """One-shot: render ``weights (n_faces, n_shapes)`` with a fresh :class:`Renderer`."""
    with Renderer(model, **options) as r:  # type: ignore[arg-type]
        return r.render(weights)
