"""The browser face viewer in Debian's Chromium (SwiftShader WebGL 2) driven by Playwright."""

from __future__ import annotations

import io
import time
from typing import Any

import numpy as np
import pytest
from PIL import Image

from emogen.correct import model_correctives
from emogen.render.examples import example_weights
from tests.web import viewer_site as vs

pytestmark = pytest.mark.browser

# Fixtures of viewer_site.py, visible to pytest in this module.
viewer_build = vs.viewer_build
viewer_site = vs.viewer_site
chromium = vs.chromium
Site = vs.Site

# A sanity bound only: the < 3 s page-ready target is measured by benchmarks/bench_viewer.py
# (timed assertions in tests flake on a loaded 2-core machine).
READY_LIMIT_S = 20.0
# Browser vs offscreen, same face at 512²: see test_browser_and_offscreen_agree.
MAX_MEAN_ABS = 0.75
MAX_FRACTION_OFF = 0.015
OFF_LEVELS = 40


@pytest.fixture(scope="module")
def site(viewer_site: Site) -> Site:
    return viewer_site


def open_viewer(
    browser: Any, site: Site, query: str = "", width: int = 1400, scale: int = 1
) -> tuple[Any, Any, float]:
    """A fresh context (empty cache) and page; returns (context, page, seconds to ready)."""
    context = browser.new_context(
        viewport={"width": width, "height": 700}, device_scale_factor=scale
    )
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    t = time.perf_counter()
    page.goto(f"{site.url}/index.html{query}")
    page.wait_for_function("window.emogenReady === true", timeout=30_000, polling=50)
    seconds = time.perf_counter() - t
    assert not errors, errors
    assert page.evaluate("window.emogen.error") is None
    return context, page, seconds


def screenshot(locator: Any) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(locator.screenshot())).convert("RGB"))


def assert_agrees(shot: np.ndarray, expected: np.ndarray, i: int) -> float:
    """The browser's face ``shot`` is the offscreen ``expected`` within the limits; its mean."""
    d = np.abs(shot - expected)
    assert d.mean() < MAX_MEAN_ABS, (i, d.mean())
    assert (d.max(-1) > OFF_LEVELS).mean() < MAX_FRACTION_OFF, i
    return float(d.mean())


def weights_of(model: Any, *named: dict[str, float]) -> list[list[float]]:  # type: ignore[no-untyped-def]
    return [model.rig.weights_from_names(d).tolist() for d in named]


def test_ten_faces_load_fast_and_follow_their_weights(chromium: Any, site: Site, ict_model) -> None:  # type: ignore[no-untyped-def]
    # best of two cold loads: a load spike from other processes on this 2-core machine is not the page's
    timings = []
    for attempt in range(2):
        context, page, seconds = open_viewer(chromium, site)
        timings.append(seconds)
        if attempt == 0:
            context.close()
    assert min(timings) < READY_LIMIT_S, timings
    assert page.evaluate("window.emogen.mode") == "webgl"
    # morph targets: the shapes, then the correctives (a shorter vector leaves them at 0)
    targets = [*ict_model.shape_names, *model_correctives(ict_model).names]
    assert page.evaluate("window.emogen.shapeNames") == targets
    assert "ICT-FaceKit © 2020 USC ICT, MIT licence" in page.inner_text("footer")
    faces = [
        {},
        {"jawOpen": 1.0},
        {"mouthSmile": 1.0, "jawOpen": 0.3},
        {"eyeBlink": 1.0},
        {"browInnerUp": 1.0},
        {"eyeLookLeft": 1.0},
        {"PupilDilate": 1.0},
        {"mouthFunnel": 1.0},
        {"noseSneer": 1.0},
        {"cheekPuff": 1.0},
    ]
    page.evaluate("w => window.emogen.setFaces(w)", weights_of(ict_model, *faces))
    slots = page.locator(".face")
    assert slots.count() == 10
    shots = [screenshot(slots.nth(i)) for i in range(10)]
    for shot in shots:
        assert shot.shape == (256, 256, 3)
        assert np.any(shot != 128, axis=-1).mean() > 0.4  # a face in every slot
    for s in shots[1:]:  # every face differs from the neutral somewhere, clearly
        d = np.abs(shots[0].astype(int) - s).max(-1)
        assert (d > 30).sum() > 20
    # named weights work too; a wrong length is refused
    page.evaluate("() => window.emogen.setFaces([{jawOpen: 1}])")
    assert np.array_equal(screenshot(slots.nth(0)), shots[1])
    with pytest.raises(Exception, match=f"expected at most {len(targets)} weights"):
        page.evaluate(f"() => window.emogen.setFaces([Array({len(targets) + 1}).fill(0)])")
    context.close()


def test_browser_and_offscreen_agree(chromium: Any, site: Site, ict_model) -> None:  # type: ignore[no-untyped-def]
    """Same face, same size (512²): mean absolute pixel difference < 0.75 of 255, against the
    offscreen PNGs participants see (2× supersampled).

    The site's GLB carries the identity's skin textures (WebP) and fitted camera; the offscreen
    renderer draws the same identity with the same appearance (the same WebP bytes, decoded by
    Pillow instead of Chromium) and fits the same camera. Both compile the same shade.glsl with
    the same look.json constants. The page runs at device pixel ratio 2 (a HiDPI screen): its
    1024² canvas, box-filtered to 512² as the offscreen renderer filters its 1024² framebuffer,
    is the same 2× supersampling, so both sample the same texture mip levels and smooth the
    same edges (SwiftShader itself draws without MSAA: it speckles). What is left is (a)
    normals: exact per face offscreen, blended int8 morph-target normals in the browser
    (largest on the smile); (b) int16 positions (0.008 mm); (c) rasterisation and WebP decoding
    rounding. Measured: 0.25-0.52. At device pixel ratio 1 against the supersampled PNGs the
    smile reaches 0.85 (anti-aliasing of the fitted, larger face and finer mip levels). The
    limit catches real disagreement — checked below against an offscreen face that differs a
    little (jawOpen 0.2) — and a camera 0.3° wider gives ≈ 1.6, a key light 5 % brighter
    ≈ 1.0, skin 3 % lighter ≈ 2.2 (measured untextured).
    """
    from emogen.render.gl import downsample

    context, page, _ = open_viewer(
        chromium, site, "?faces=1&size=512&columns=1", width=600, scale=2
    )
    named = [{}, {"jawOpen": 1.0}, {"eyeLookLeft": 1.0, "eyeLookUp": 0.5}, {"PupilDilate": 1.0}]
    w = np.array(weights_of(ict_model, *named))
    _, smile = example_weights(ict_model, "smile")
    _, open_mouth = example_weights(ict_model, "open_mouth")
    w = np.concatenate([w, smile, open_mouth])
    assert page.evaluate("window.emogen.view.textured") is True
    with vs.offscreen_renderer(ict_model, 512, supersample=2) as r:
        offscreen = r.render(w).astype(int)
        control = r.render(np.array(weights_of(ict_model, {"jawOpen": 0.2}))).astype(int)[0]
    slot = page.locator(".face").first
    for i in range(len(w)):
        page.evaluate("w => window.emogen.setFaces([w])", w[i].tolist())
        device = screenshot(slot)
        assert device.shape == (1024, 1024, 3)
        shot = downsample(device, 2).astype(int)
        assert_agrees(shot, offscreen[i], i)
        if i == 0:
            assert np.abs(shot - control).mean() > MAX_MEAN_ABS  # the test can tell faces apart
    context.close()


def test_corrected_prototypes_agree_with_offscreen(chromium: Any, site: Site, ict_model) -> None:  # type: ignore[no-untyped-def]
    """The happy, angry, sad and fearful prototypes, corrected (the reach shapes active:
    the nasolabial fold, the lid bulge, the knit brows, AU1+4, the lip stretch), and surprise,
    sent to the page as a study sends them — shape weights then corrective weights — agree with
    the offscreen renderer's corrected face within the same limit as uncorrected faces.

    Fear was 0.93/255 off (a dark crease band on the upper lids) until the reach shapes' normal
    deltas made the viewer's linear blend of normals exact at their apex (docs/render.md)."""
    from emogen.correct import correct_faces
    from emogen.render.gl import downsample

    rig = ict_model.rig
    w = np.array(
        [rig.weights_from_names({g: 1.0 for g in rig.emotions[e].core}) for e in
         ("happy", "angry", "sad", "surprised", "fearful")]
    )  # fmt: skip
    model, _ = vs.identity_model(ict_model, vs.IDENTITY)
    r = correct_faces(model, w)
    full = np.concatenate([r.weights, r.correctives], axis=1)
    reach = [i for i, n in enumerate(r.combinational_names) if n.startswith("reach_")]
    assert r.combinational[:, reach].max() == 1.0
    context, page, _ = open_viewer(
        chromium, site, "?faces=1&size=512&columns=1", width=600, scale=2
    )
    with vs.offscreen_renderer(ict_model, 512, supersample=2) as off:
        offscreen = off.render(w, correct=True).astype(int)
        uncorrected = off.render(w).astype(int)
    slot = page.locator(".face").first
    for i in range(len(w)):
        page.evaluate("w => window.emogen.setFaces([w])", full[i].tolist())
        shot = downsample(screenshot(slot), 2).astype(int)
        off_by = assert_agrees(shot, offscreen[i], i)
        # and the correctives are seen: the uncorrected face is further away
        assert np.abs(shot - uncorrected[i]).mean() > off_by
    context.close()


def test_wrinkle_strength_reaches_the_viewer(chromium: Any, site: Site, ict_model) -> None:  # type: ignore[no-untyped-def]
    """female-dark-v3 (wrinkle_strength 2): its GLB records the strength with its appearance,
    the page's material applies it, and the corrected angry face agrees with the offscreen
    renderer's within the limits above. Where the strength shows (pixels the offscreen faces at
    strength 1 and 2 differ by > 4 levels: the furrows), the page is far closer to strength 2
    than to 1 — a page that ignored the GLB's strength would draw strength 1."""
    from emogen.correct import correct_faces
    from emogen.render.gl import downsample

    name = "female-dark-v3"
    vs.export_site_glb(ict_model, site.folder / f"{name}.glb", name)
    model, appearance = vs.identity_model(ict_model, name)
    assert appearance.wrinkle_strength == 2.0
    rig = model.rig
    w = np.array([rig.weights_from_names({g: 1.0 for g in rig.emotions["angry"].core})])
    r = correct_faces(model, w)
    full = np.concatenate([r.weights, r.correctives], axis=1)
    context, page, _ = open_viewer(
        chromium, site, f"?faces=1&size=512&columns=1&model={name}.glb", width=600, scale=2
    )
    with vs.offscreen_renderer(ict_model, 512, name=name, supersample=2) as off:
        strong = off.render(w, correct=True).astype(int)[0]
        off._gl.set_wrinkle_strength(1.0)  # the same painted skin at the old strength
        plain = off.render(w, correct=True).astype(int)[0]
    page.evaluate("w => window.emogen.setFaces([w])", full[0].tolist())
    shot = downsample(screenshot(page.locator(".face").first), 2).astype(int)
    assert_agrees(shot, strong, 0)
    furrows = np.abs(strong - plain).max(-1) > 4
    assert furrows.sum() > 200, furrows.sum()
    near, far = (np.abs(shot - x)[furrows].mean() for x in (strong, plain))
    assert near < 0.5 * far, (near, far)
    context.close()


def test_oval_framing_agrees_with_offscreen(chromium: Any, site: Site, ict_model) -> None:  # type: ignore[no-untyped-def]
    """framing=oval: the page lays look.json's oval over each face (CSS), the offscreen
    renderer masks its images (emogen.render.images.apply_oval); same face, same limits as
    above. Outside the oval both are the bare background; the same face without the oval
    differs by far more than the limit (the check can fail)."""
    from emogen.render.gl import downsample

    context, page, _ = open_viewer(
        chromium, site, "?faces=1&size=512&columns=1&framing=oval", width=600, scale=2
    )
    _, smile = example_weights(ict_model, "smile")
    w = np.concatenate([np.array(weights_of(ict_model, {})), smile])
    with vs.offscreen_renderer(ict_model, 512, supersample=2, framing="oval") as r:
        offscreen = r.render(w).astype(int)
    with vs.offscreen_renderer(ict_model, 512, supersample=2) as r:
        bare = r.render(w[:1]).astype(int)[0]
    slot = page.locator(".face").first
    background = np.round(255 * np.array(r.look.background_srgb)).astype(int)
    for i in range(len(w)):
        page.evaluate("w => window.emogen.setFaces([w])", w[i].tolist())
        shot = downsample(screenshot(slot), 2).astype(int)
        d = np.abs(shot - offscreen[i])
        assert d.mean() < MAX_MEAN_ABS, (i, d.mean())
        assert (d.max(-1) > OFF_LEVELS).mean() < MAX_FRACTION_OFF, i
        assert np.all(shot[:, :40] == background) and np.all(offscreen[i][:, :40] == background)
    assert np.abs(offscreen[0] - bare).mean() > 10 * MAX_MEAN_ABS
    context.close()


def test_webgl_less_fallback_shows_server_pngs(playwright_api: Any, site: Site, ict_model) -> None:  # type: ignore[no-untyped-def]
    browser = vs.launch(playwright_api, "--disable-3d-apis")
    try:
        context, page, _ = open_viewer(browser, site, "?faces=3&size=128&columns=3")
        assert page.evaluate("window.emogen.mode") == "fallback"
        images = page.locator(".face img")
        assert images.count() == 3
        assert page.evaluate(
            "[...document.images].every(i => i.complete && i.naturalWidth === 128)"
        )
        before = screenshot(images.nth(1)).astype(int)
        page.evaluate("w => window.emogen.setFaces(w)", weights_of(ict_model, {}, {"jawOpen": 1.0}))
        after = screenshot(images.nth(1)).astype(int)
        assert np.abs(before - after).mean() > 1.0  # the server rendered the open mouth
        assert "ICT-FaceKit" in page.inner_text("footer")
        context.close()
    finally:
        browser.close()
