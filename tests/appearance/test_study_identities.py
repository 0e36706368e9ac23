"""A study's identities reach its stimuli: the server's no-WebGL PNGs draw each identity's shape
and appearance (the lab's own and the presets), the same pixels as the renderer itself."""

from __future__ import annotations

import asyncio

import numpy as np

from emogen.appearance.identities import PRESETS
from emogen.render.images import png_bytes
from emogen.render.renderer import Renderer
from emogen.study.config import study_from_dict
from emogen.web.faces import FacePNGs


def test_face_pngs_draw_each_identity_with_its_appearance(ict_model) -> None:  # type: ignore[no-untyped-def]
    config = study_from_dict(
        {
            "identities": ["male-dark", "lab_face"],
            "identity": {"lab_face": {"shape": [1.0, -0.5], "skin_tone": 4.5, "hair": "none"}},
        }
    )
    identities = config.study_identities()
    w = np.zeros(ict_model.n_shapes)
    w[ict_model.shape_names.index("jawOpen")] = 0.5
    faces = FacePNGs(ict_model, size=64, correct=False, identities=identities)
    try:
        got = {n: asyncio.run(faces.render(w, n)) for n in ("male-dark", "lab_face", "generic")}
    finally:
        faces.close()
    for name, png in got.items():
        ident = identities.get(name, PRESETS.get(name))
        assert ident is not None
        with Renderer(
            ict_model.with_identity(ident.shape), size=64, appearance=ident.appearance
        ) as r:
            assert png == png_bytes(r.render(w[None])[0]), name
    assert len(set(got.values())) == 3
