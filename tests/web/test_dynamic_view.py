# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""What the server sends the page of a face that moves, checked against the records: each face
of a dynamic generation (and the rated face) carries ``motion``; the page's formula (docs/ga.md,
"Dynamic faces", written here as a plain loop) evaluated on it gives, at every time, the
weights ``emogen.ga.motion.frames`` computes from the stored genes, timing and keyframe
correctives. A static block's faces carry none. The server's image of a moving face (browsers
without WebGL) is the strip of its frames: 11 frames side by side, the first at rest."""

from __future__ import annotations

import io
import json
import math
from typing import Any

import numpy as np
from fastapi.testclient import TestClient
from PIL import Image
from sqlalchemy import select

from emogen.ga.genome import DynamicGenome
from emogen.ga.motion import STRIP_FRAMES, frames
from emogen.tasks.evolve.tables import FaceCurveRow, FaceRow, PopulationRow
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401

STUDY = {
    "name": "moving-view",
    "emotions": ["happy"],
    "seed": 3,
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 2},
    "blocks": [
        {"task": "evolve", "dynamic": {"clip_s": 1.5, "hold_s": 0.5, "keyframes": 9}},
        {"task": "evolve"},
    ],
}


def page_weights(face: dict[str, Any], t: float) -> list[float]:
    """The page's weights at clip time t, by the documented formula, one number at a time."""
    m = face["motion"]
    out = [0.0] * (len(m["curves"]) + (len(m["keyframes"][0]) if m["keyframes"] else 0))
    for k, (on, peak, off, rise, fall) in enumerate(m["curves"]):
        if face["weights"][k] == 0:
            continue
        if t <= peak:
            x, slope = min(max((t - on) / (peak - on), 0.0), 1.0), rise
        else:
            x, slope = min(max((off - t) / (off - peak), 0.0), 1.0), fall
        out[k] = face["weights"][k] * (3 * x**2 - 2 * x**3 + slope * (x**3 - 2 * x**2 + x))
    keys = m["keyframes"]
    if keys:
        pos = t / m["clip_s"] * (len(keys) - 1)
        left = min(math.floor(pos), len(keys) - 2)
        s = pos - left
        for c in range(len(keys[0])):
            a, b = keys[left][c], keys[left + 1][c]
            out[len(m["curves"]) + c] = a + (b - a) * s
    return out


def recorded(app: Any, face_id: int) -> tuple[np.ndarray, np.ndarray]:
    """(genes (K, 6), keyframe correctives (F, C)) of a face of the latest generation."""
    with app.state.store.read() as db:
        face = db.scalars(
            select(FaceRow)
            .join(PopulationRow, FaceRow.population_id == PopulationRow.id)
            .where(FaceRow.face_id == face_id)
            .order_by(PopulationRow.id.desc())
        ).first()
        curve = db.scalar(
            select(FaceCurveRow).where(
                FaceCurveRow.population_id == face.population_id,
                FaceCurveRow.position == face.position,
            )
        )
        amp = np.asarray(json.loads(face.genes))[:, None]
        genes = np.concatenate([amp, np.asarray(json.loads(curve.timing))], axis=1)
        return genes, np.asarray(json.loads(curve.keyframe_correctives))


def test_the_page_is_sent_what_the_records_play(db_url: str, ict_model: Any) -> None:
    from emogen.study.config import study_from_dict
    from emogen.web import create_app

    app = create_app(study_from_dict(STUDY), db_url, model=ict_model)
    genome = DynamicGenome(clip_s=1.5, hold_s=0.5, keyframes=9)
    times = np.linspace(0, 1.5, 31)
    try:
        with TestClient(app) as client:
            r = client.post("/api/sessions", json={"participant_id": "m1"})
            token = r.json()["token"]
            step = lambda body: client.post(f"/api/s/{token}/step", json=body).json()  # noqa: E731
            state = step({"command": "begin", "key": "key-begin-000000"})
            faces = state["view"]["population"]["faces"]
            assert len(faces) == 10 and all("motion" in f for f in faces)
            moving = 0
            for face in faces:
                m = face["motion"]
                assert (m["clip_s"], m["hold_s"], len(m["keyframes"])) == (1.5, 0.5, 9)
                genes, keyed = recorded(app, face["id"])
                want = frames(genome, genes[None], keyed[None], times, ict_model.rig.expand)[0]
                got = np.array([page_weights(face, t) for t in times])
                np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
                moving += want[:, : ict_model.n_shapes].max() > 0.1
            assert moving >= 8  # generation 0's faces move (a blank one may stand still)
            # a reload reads the population back from the database: the same faces, the same
            # motion, number for number, as the step's answer (made from the faces in memory)
            again = client.get(f"/api/s/{token}/state").json()
            assert again["view"]["population"]["faces"] == faces
            # the server's image of a moving face: the strip of its frames
            mover = next(f for f in faces if max(f["weights"]) > 0.3)
            png = client.get(f"/api/s/{token}/faces/{mover['id']}.png?trial=0&attempt=0")
            assert png.status_code == 200
            strip = np.asarray(Image.open(io.BytesIO(png.content)).convert("RGB"))
            height, width, _ = strip.shape
            assert width == STRIP_FRAMES * height
            frame = [strip[:, k * height : (k + 1) * height].astype(int) for k in range(11)]
            assert max(np.abs(f - frame[0]).mean() for f in frame) > 0.5  # it moves
            np.testing.assert_array_equal(frame[0], frame[-1])  # at rest at both ends
            # choose through the block: the rated face moves too
            for generation in (0, 1):
                ids = [f["id"] for f in state["view"]["population"]["faces"]]
                state = step({"command": "select", "key": f"key-select-{generation:06d}", "trial": 0,
                              "attempt": 0, "generation": generation, "elite": ids[0],
                              "others": []})  # fmt: skip
            assert "motion" in state["view"]["rating"]["face"]
            assert client.get(f"/api/s/{token}/state").json()["view"] == state["view"]
            state = step({"command": "rate", "key": "key-rate-0000000", "trial": 0, "value": 4})
            # the static block's faces stand still, and their image is one face
            faces = state["view"]["population"]["faces"]
            assert not any("motion" in f for f in faces)
            png = client.get(f"/api/s/{token}/faces/{faces[0]['id']}.png?trial=1&attempt=0")
            still = Image.open(io.BytesIO(png.content))
            assert still.width == still.height
    finally:
        app.state.store.dispose()
