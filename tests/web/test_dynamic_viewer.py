"""Faces that move, in the browser viewer (Debian's Chromium, SwiftShader WebGL 2, Playwright).

A dynamic face — the happy prototype's genes with the jaw, each with its own time course, its
correctives at 21 keyframes as the GA computes them — is given to the viewer as the study's
view gives it (peak weights and ``motion``). The viewer plays it (its pixels change over time),
and the frame it shows at clip time t, held there by ``scrub``, is the offscreen renderer's
face at t: the weights of ``emogen.ga.motion.frames`` (the closed-form curves, the keyframe
correctives interpolated), blended in numpy — the same limits as a still face
(tests/web/test_viewer.py), and nearer the offscreen face at t than at another time.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import pytest

from emogen.correct import correct_faces
from emogen.correct.faces import corrector_for
from emogen.ga.genome import DynamicGenome
from emogen.ga.motion import correct_keyframes, frames, shape_curves
from tests.web import viewer_site as vs
from tests.web.test_kept_frames import COUNT_DRAWS
from tests.web.test_viewer import MAX_MEAN_ABS, assert_agrees, open_viewer, screenshot

pytestmark = pytest.mark.browser

viewer_build = vs.viewer_build
viewer_site = vs.viewer_site
chromium = vs.chromium
Site = vs.Site

TIMES = (0.15, 0.45, 0.8, 1.1)  # 1.1: between keyframes, correctives on
TWO_FRAMES = "() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)))"


# The held face's clip time, then replay, then its clip time, in one task of the page.
REPLAY = """() => {
  const view = window.emogen.view;
  const held = view.clipTime(0);
  view.replay();
  return [held, view.clipTime(0)];
}"""


def moving_face(ict_model: Any) -> tuple[DynamicGenome, np.ndarray, np.ndarray, Any]:
    """(genome, genes (1, K, 6), keyframe correctives (1, F, C), the identity's model)."""
    rig = ict_model.rig
    model, _ = vs.identity_model(ict_model)
    genome = DynamicGenome()
    names = rig.gene_names()
    genes = np.zeros((1, len(names), 6))
    for g in (*rig.emotions["happy"].core, "jawOpen"):
        genes[0, names.index(g), 0] = 1.0 if g != "jawOpen" else 0.5
    genes[0, :, 1:] = np.random.default_rng(3).random((len(names), 5))

    def correct(w: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:
        r = correct_faces(model, w)
        return r.corrective_names, r.correctives

    _, keyed = correct_keyframes(genome, genes, rig.expand, correct)
    return genome, genes, keyed, model


def motion_of(
    genome: DynamicGenome, genes: np.ndarray, keyed: np.ndarray, rig: Any
) -> dict[str, Any]:
    """The face as the study's view sends it (emogen.tasks.evolve.view)."""
    peak = rig.expand(genes[:, :, 0])[0]
    return {
        "weights": peak.tolist(),
        "motion": {
            "clip_s": genome.clip_s,
            "hold_s": genome.hold_s,
            "curves": shape_curves(genome, genes[0, :, 1:], rig.expansion_matrix()).tolist(),
            "keyframes": keyed[0].tolist(),
        },
    }


def offscreen_frames(renderer: Any, model: Any, weights: np.ndarray) -> np.ndarray:
    """Faces of full weights (n, S + C): shapes blended, corrective offsets added, in numpy."""
    s = model.n_shapes
    vertices = model.evaluate(weights[:, :s].astype(np.float32))
    rows = corrector_for(model).corrective_rows
    vertices += (weights[:, s:].astype(np.float32) @ rows).reshape(vertices.shape)
    return np.asarray(renderer.render_vertices(vertices, targets=weights.astype(np.float32)))


def test_a_moving_face_plays_and_its_frame_at_t_is_the_offscreen_face(
    chromium: Any, viewer_site: Site, ict_model: Any
) -> None:
    from emogen.render.gl import downsample

    genome, genes, keyed, model = moving_face(ict_model)
    rig = ict_model.rig
    shown = frames(genome, genes, keyed, np.array(TIMES), rig.expand)[0]  # (T, S + C)
    assert np.ptp(shown[:, model.n_shapes :], axis=0).max() > 0.05  # correctives move too
    context, page, _ = open_viewer(
        chromium, viewer_site, "?faces=1&size=512&columns=1", width=600, scale=2
    )
    slot = page.locator(".face").first
    page.evaluate("face => window.emogen.view.play([face])", motion_of(genome, genes, keyed, rig))
    # it plays: the pixels change from frame to frame over the loop (2 s)
    shots = []
    for _ in range(6):
        page.wait_for_timeout(300)
        shots.append(screenshot(slot).astype(int))
    changes = [np.abs(a - b).mean() for a, b in itertools.pairwise(shots)]
    assert max(changes) > 1.0, changes
    assert page.evaluate("window.emogen.view.frames") >= 6
    with vs.offscreen_renderer(ict_model, 512, supersample=2) as r:
        offscreen = offscreen_frames(r, model, shown).astype(int)
    for i, t in enumerate(TIMES):
        page.evaluate("t => window.emogen.view.scrub(0, t)", t)
        page.evaluate(TWO_FRAMES)
        assert page.evaluate("window.emogen.view.clipTime(0)") == t
        shot = downsample(screenshot(slot), 2).astype(int)
        assert_agrees(shot, offscreen[i], i)
        # the test tells times apart: the face at another time is further than the limit
        other = offscreen[(i + 2) % len(TIMES)]
        assert np.abs(shot - other).mean() > MAX_MEAN_ABS, (t, TIMES[(i + 2) % len(TIMES)])
    # replay: the held face plays along again, from the clip's start (read in one task of the
    # page: two calls on a loaded machine were once 0.6 s apart)
    held, started = page.evaluate(REPLAY)
    assert held == TIMES[-1] and 0 <= started < 0.05, (held, started)
    page.wait_for_timeout(300)
    assert page.evaluate("window.emogen.view.clipTime(0)") != started  # it plays, not held
    context.close()


# Face 0's clip frames: every one kept (none left to draw ahead, every copy made).
CLIP_KEPT = """() => {
  const v = window.emogen.view, kept = v.kept.get(0), shown = v.faces[0].shown;
  return Boolean(kept && shown) && kept.complete(Math.max(0, kept.find(shown)));
}"""


def test_a_moving_face_plays_kept_frames_that_are_its_live_draws(
    chromium: Any, viewer_site: Site, ict_model: Any
) -> None:
    """The clip's grid frames (viewer/motion.js FRAME_RATE), each drawn once and kept
    (viewer/kept.js), are what the face shows while it plays; held at a grid time, the kept
    frame on screen equals, pixel for pixel, the live WebGL draw of the face at that time."""
    genome, genes, keyed, _ = moving_face(ict_model)
    context, page, _ = open_viewer(chromium, viewer_site, "?faces=1&size=445")
    slot = page.locator(".face").first
    page.evaluate(
        "face => window.emogen.view.play([face])", motion_of(genome, genes, keyed, ict_model.rig)
    )
    steps = page.evaluate("window.emogen.view.clips[0].steps")
    assert steps == int(np.ceil(genome.clip_s * 30 - 1e-9))  # a 30 frames/s grid
    page.wait_for_function(CLIP_KEPT, timeout=180_000, polling=200)
    assert page.evaluate("window.emogen.view.kept.get(0).frames.size") == steps + 1
    # playing, every picture is a kept frame: no live draw
    page.evaluate(COUNT_DRAWS)
    page.wait_for_timeout(1500)
    assert page.evaluate("window.liveDraws") == 0
    picks = [2, steps // 3, (2 * steps) // 3, steps - 3]
    times = page.evaluate("ks => ks.map((k) => window.emogen.view.clips[0].gridTime(k))", picks)
    kept = {}
    for k, t in zip(picks, times, strict=True):
        page.evaluate("t => window.emogen.view.scrub(0, t)", t)
        page.evaluate(TWO_FRAMES)
        state = page.evaluate("window.emogen.view.keptState(0)")
        assert state["shown"] == k and state["showing"] == k, (k, state)
        kept[k] = screenshot(slot)
    assert page.evaluate("window.liveDraws") == 0
    for a, b in itertools.combinations(
        picks, 2
    ):  # the frames differ: equality below means the right one
        assert (np.abs(kept[a].astype(int) - kept[b]).max(-1) > 20).sum() > 100, (a, b)
    page.evaluate("() => window.emogen.view.keep(0, null)")  # forgotten: drawn live from now on
    for k, t in zip(picks, times, strict=True):
        page.evaluate("t => window.emogen.view.scrub(0, t)", t)
        page.evaluate(TWO_FRAMES)
        assert page.evaluate("window.emogen.view.keptState(0)") is None
        assert np.array_equal(screenshot(slot), kept[k]), k
    assert page.evaluate("window.liveDraws") > 0
    # the tiles resized: the clip's frames are kept again, at the new size
    page.evaluate(
        "() => document.getElementById('faces').style.setProperty('--face-size', '400px')"
    )
    page.wait_for_function(
        f"() => window.emogen.view.kept.get(0)?.frames.get(0)?.rect[2] === 400 && ({CLIP_KEPT})()",
        timeout=180_000,
        polling=200,
    )
    state = page.evaluate("window.emogen.view.keptState(0)")
    assert state["kept"] == steps + 1 and state["showing"] == state["shown"] >= 0, state
    # so large that 39 frames exceed the 256 MiB (1700² px × 4 B × 39 = 451 MB): drawn live
    page.evaluate(
        "() => document.getElementById('faces').style.setProperty('--face-size', '1700px')"
    )
    page.wait_for_function("() => window.emogen.view.keptState(0) === null", timeout=30_000)
    page.evaluate(COUNT_DRAWS)
    page.evaluate("() => window.emogen.view.scrub(0, null)")
    page.wait_for_function("() => window.liveDraws >= 3", timeout=60_000)
    context.close()
