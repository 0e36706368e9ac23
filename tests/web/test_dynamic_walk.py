"""One participant evolves expressions that move in ``examples/dynamic.toml`` as written, served
by ``emogen serve``, in Debian's Chromium: on a 1366×768 desktop (mouse and keyboard) and on a
phone upright (390×844, touch), through the whole dynamic block — every generation of every
emotion, tiles chosen at changing places, one tile stepped through with the slider, the clips
replayed on demand — and the records are checked against what the page was sent and showed:
every face shown (ids in tile order, peak weights), the curves the page played for each chosen
tile (each shape's onset, peak and offset in seconds and its slopes: the export's `face_curves`
row of the gene that moves it), the selections, and the final face. A reload mid-block resumes
the same generation with the same clips; the phone turned to landscape keeps all ten faces
playing and the choices made. Without WebGL (the context refused) the page shows the server's
strips of frames and every selection records it (``fallback``).
"""

from __future__ import annotations

import tomllib
import uuid
from collections.abc import Iterator
from io import BytesIO
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from benchmarks.bench_study import ServerProcess
from PIL import Image, ImageDraw, ImageFont

from emogen.study.export import export_tables
from emogen.study.replay import replay_session
from emogen.study.storage import Store
from tests.web.test_dynamic_browser import clip_times, replay_now, tiles, tiles_moving
from tests.web.test_study_browser import CSP_PROBE, browser, shown_faces, viewer_bundle, wait_ready
from tests.web.viewer_site import REPO, screenshot_folder

pytestmark = [pytest.mark.browser, pytest.mark.slow]
_ = (browser, viewer_bundle)  # fixtures, requested by name

EXAMPLE = REPO / "examples" / "dynamic.toml"

#: Both walks choose every round of the first trial on the page (a whole evolution:
#: examples/dynamic.toml's 10 generations after the first) and rate its face there. The
#: session's other trials go through the participant API: each round of ten moving
#: faces takes about 30 s in software GL on the shared 2-core machine at load 3 (10-60 s under
#: heavier load; the whole desktop test 6 min at load 3), and all 44
#: rounds of the four trials took over 20 minutes there.
GENERATIONS = 10

#: Where the desktop walk leaves the final face's `face_curves` rows (its first trial's,
#: rated on the page): `emogen render clip` makes docs/images/dynamic-walk-final.webp of it.
FINAL_CURVES = Path("/tmp/emogen-dynamic-walk-final-curves.csv")

#: A browser without WebGL: every canvas refuses a WebGL context (as a machine without a GPU
#: driver, or with WebGL switched off, answers).
NO_WEBGL = """
const original = HTMLCanvasElement.prototype.getContext;
HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
  return /webgl/i.test(kind) ? null : original.call(this, kind, ...rest);
};
"""


@pytest.fixture(scope="module")
def example(
    tmp_path_factory: pytest.TempPathFactory, ict_dir: Path, viewer_bundle: Path
) -> Iterator[tuple[ServerProcess, str]]:
    tmp = tmp_path_factory.mktemp("dynamic-example")
    db = f"sqlite:///{tmp / 'study.sqlite'}"
    srv = ServerProcess(EXAMPLE, db, ict_dir, tmp / "server.log")
    yield srv.start(), db
    srv.stop()


def is_state(response: Any) -> bool:
    """The server's answer that carries the page's next screen (a step, or a reload's state)."""
    url = response.url
    return "/api/s/" in url and (url.endswith("/step") or url.endswith("/state"))


class Walk:
    """One participant's page and everything the server sent it, screen by screen."""

    def __init__(self, page: Any, phone: bool) -> None:
        self.page, self.phone = page, phone
        self.screens: dict[tuple[int, int], list[dict[str, Any]]] = {}  # (trial, gen) → faces
        self.chosen: dict[tuple[int, int], tuple[int, list[int]]] = {}
        self.on_page: set[tuple[int, int]] = set()  # the screens chosen on the page
        self.rated: dict[int, dict[str, Any]] = {}  # trial → the rated face as sent
        self.state: dict[str, Any] = {}
        self.api = ""  # the session's participant API: /api/s/<token>

    def press(self, selector: str) -> dict[str, Any]:
        """Press a button and keep the state the server answered with."""
        with self.page.expect_response(is_state, timeout=120_000) as answer:
            self.touch(self.page.locator(selector))
        self.state = answer.value.json()
        self.api = answer.value.url.rsplit("/", 1)[0]
        return self.state

    def send(self, body: dict[str, Any]) -> dict[str, Any]:
        """A step sent to the participant API directly, not through the page."""
        body = {**body, "key": uuid.uuid4().hex}
        answer = self.page.request.post(f"{self.api}/step", data=body)
        assert answer.ok, answer.text()
        self.state = answer.json()
        return self.state

    def reload(self) -> None:
        """The page reloaded; the state it is given kept."""
        with self.page.expect_response(is_state, timeout=120_000) as answer:
            self.page.reload()
        self.state = answer.value.json()

    def answer(self, until: Any) -> None:
        """Screens answered through the participant API, as :meth:`choose` would on the page,
        until ``until(state)``; the dynamic ones kept to check against the records."""
        while not until(self.state):
            trial = self.state["progress"]["trial"]
            if self.state["trial"]["status"] == "rating":
                self.send({"command": "rate", "trial": trial, "value": 4})
                continue
            view = self.state["view"]
            faces, generation = view["population"]["faces"], view["generation"]
            elite = (3 * generation + trial) % 10
            if all("motion" in f for f in faces):
                self.screens[(trial, generation)] = faces
                self.chosen[(trial, generation)] = (faces[elite]["id"], [])
            self.send({"command": "select", "trial": trial, "generation": generation,
                       "attempt": self.state["trial"]["attempt"], "elite": faces[elite]["id"],
                       "others": []})  # fmt: skip

    def touch(self, locator: Any) -> None:
        if self.phone:
            locator.tap()
        else:
            locator.click()

    def face(self, position: int) -> Any:
        return self.page.locator("#grid > .cell .face").nth(position)

    def screen(self) -> tuple[int, int, list[dict[str, Any]]]:
        """The trial screen shown now: (trial, generation, its faces as the server sent them),
        after checking that the page shows those faces in that order, all of them moving."""
        view = self.state["view"]
        trial, generation = self.state["progress"]["trial"], view["generation"]
        faces = view["population"]["faces"]
        wait_ready(self.page, "trial")
        assert shown_faces(self.page) == [f["id"] for f in faces]
        assert all("motion" in f for f in faces)
        times = grid_times(self.page)  # every tile plays its clip (a blank face stands still)
        assert sum(t is not None for t in times) >= 8, times
        self.screens[(trial, generation)] = faces
        return trial, generation, faces

    def choose(self, trial: int, generation: int, ids: list[int]) -> None:
        """Best at a place that moves with the generation and trial, one or two others."""
        elite = (3 * generation + trial) % 10
        others = [(elite + 4) % 10] + ([(elite + 7) % 10] if generation % 2 else [])
        self.touch(self.face(elite))
        for k in others:
            self.touch(self.face(k))
        self.chosen[(trial, generation)] = (ids[elite], [ids[k] for k in others])
        self.on_page.add((trial, generation))
        self.press("#next")

    def rate(self, trial: int, value: int) -> None:
        wait_ready(self.page, "rating")
        self.rated[trial] = self.state["view"]["rating"]["face"]
        self.touch(self.page.locator("#rating-scale").get_by_label(str(value), exact=True))
        self.press("#rate")


def grid_times(page: Any) -> list[float | None]:
    """The clip time each of the ten tiles shows now, in tile order (None: a face that does not
    move); the grid's slots come first on the page."""
    times: list[float | None] = page.evaluate("window.emogenStudy.clipTimes().slice(0, 10)")
    return times


def liveliest(faces: list[dict[str, Any]]) -> int:
    """The tile whose face moves most (its largest peak weight)."""
    return int(np.argmax([max(f["weights"]) for f in faces]))


def open_walk(browser: Any, server: ServerProcess, pid: str, phone: bool, script: str = "") -> Walk:
    size = (390, 844) if phone else (1366, 768)
    context = browser.new_context(
        viewport={"width": size[0], "height": size[1]}, has_touch=phone, is_mobile=phone
    )
    context.add_init_script(CSP_PROBE + script)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.errors = errors
    walk = Walk(page, phone)
    page.goto(f"{server.url}/?PROLIFIC_PID={pid}")
    walk.touch(page.get_by_role("button", name="I agree"))
    wait_ready(page, "instructions")
    walk.press("#begin")
    display = "png" if script == NO_WEBGL else "webgl"  # the page finds out by itself
    assert page.evaluate("window.emogenStudy.display") == display
    return walk


def pictures_folder() -> Path:
    folder = screenshot_folder("dynamic-walk")
    folder.mkdir(exist_ok=True, parents=True)
    return folder


def curves_as_recorded(rows: Any, expansion: np.ndarray, genes: list[str]) -> np.ndarray:
    """Each shape's curve by the export's ``face_curves`` rows of one face (its genes shown):
    a shape a gene moves plays that gene's onset, peak and offset (s) and its two slopes
    (3 × acceleration, 3 × deceleration: docs/ga.md); a shape no gene shown moves stands still
    (NaN here: the page's row for it is never used, its weight being 0)."""
    out = np.full((expansion.shape[1], 5), np.nan)
    for row in rows.itertuples():
        shapes = expansion[genes.index(row.gene)] > 0
        out[shapes] = [
            row.onset_s, row.peak_s, row.offset_s, 3 * row.acceleration, 3 * row.deceleration
        ]  # fmt: skip
    return out


def check_records(walk: Walk, db_url: str, pid: str, ict_model: Any, fallback: bool) -> Any:
    """What the server recorded of ``pid`` against what its page was sent and showed."""
    rig = ict_model.rig
    genes = list(rig.gene_names())
    expansion = rig.expand(np.eye(len(genes)))
    store = Store(db_url)
    try:
        tables = {k: t[t.participant_id == pid] for k, t in export_tables(store).items()
                  if "participant_id" in t.columns}  # fmt: skip
        faces, curves = tables["faces"], tables["face_curves"]
        w_cols = [c for c in faces.columns if c.startswith("w_")]
        for (trial, generation), shown in walk.screens.items():
            rows = faces[(faces.trial == trial) & (faces.generation == generation)]
            rows = rows[rows.attempt == rows.attempt.max()].sort_values("position")
            assert rows.face_id.tolist() == [f["id"] for f in shown], (trial, generation)
            sent = np.array([f["weights"] for f in shown])
            np.testing.assert_allclose(sent, rows[w_cols].to_numpy(float), rtol=0, atol=1e-9)
        sel = tables["selections"]
        for (trial, generation), (elite, others) in walk.chosen.items():
            rows = sel[(sel.trial == trial) & (sel.generation == generation)].sort_values("rank")
            assert rows.face_id.tolist() == [elite, *others], (trial, generation)
            if (trial, generation) in walk.on_page:  # which display showed the faces
                assert rows.fallback.tolist() == [fallback] * len(rows)
            else:  # a step sent through the API says nothing of a display
                assert rows.fallback.isna().all()
            by_id = {f["id"]: f for f in walk.screens[(trial, generation)]}
            for face_id in (elite, *others):  # the curves the page played for a chosen tile
                played = np.array(by_id[face_id]["motion"]["curves"])
                mine = curves[(curves.trial == trial) & (curves.generation == generation)
                              & (curves.face_id == face_id)]  # fmt: skip
                want = curves_as_recorded(mine, expansion, genes)
                moving = ~np.isnan(want[:, 0])
                assert moving.any()
                np.testing.assert_allclose(played[moving], want[moving], rtol=0, atol=1e-9)
                shapes = np.array(by_id[face_id]["weights"][: expansion.shape[1]])
                assert not (shapes[~moving] > 0).any()  # every shape that moves has its gene
        finals = tables["final_faces"]
        for trial, face in walk.rated.items():  # the rated face is the final face, as played
            final = finals[finals.trial == trial]
            assert len(final) == 1
            elite = walk.chosen[(trial, max(g for t, g in walk.chosen if t == trial))][0]
            assert int(final.face_id.iloc[0]) == elite
            np.testing.assert_allclose(face["weights"], final[w_cols].to_numpy(float)[0], atol=1e-9)
            mine = curves[(curves.trial == trial) & (curves.face_id == elite)
                          & (curves.generation == final.generation.iloc[0])]  # fmt: skip
            want = curves_as_recorded(mine, expansion, genes)
            moving = ~np.isnan(want[:, 0])
            played = np.array(face["motion"]["curves"])
            np.testing.assert_allclose(played[moving], want[moving], rtol=0, atol=1e-9)
        sid = int(tables["sessions"].session_id.iloc[0])
        report = replay_session(store, sid, rig, ict_model.model_hash, model=ict_model)
        assert report.ok, report.mismatches
        return tables
    finally:
        store.dispose()


def tile_box(page: Any, position: int) -> dict[str, float]:
    box: dict[str, float] = page.locator("#grid > .cell .slot").nth(position).bounding_box()
    return box


def step_through(walk: Walk, position: int, folder: Path, name: str) -> None:
    """The slider holds the tile at ``position`` (chosen by touching it) at four times, each
    a different frame, while the others play on; a strip of the four held tiles is saved."""
    page = walk.page
    walk.touch(walk.face(position))  # chosen (and so the tile the slider steps through)
    assert page.inner_text("#scrub-face") == str(position + 1)
    slider = page.locator("#scrub").bounding_box()
    clip_s = float(page.get_attribute("#scrub", "max"))
    held, crops, values = [], [], []
    for fraction in (0.1, 0.35, 0.6, 0.85):
        at = {"x": slider["width"] * fraction, "y": slider["height"] / 2}
        if walk.phone:
            page.locator("#scrub").tap(position=at)
        else:
            page.locator("#scrub").click(position=at)
        value = float(page.input_value("#scrub"))
        values.append(value)
        assert abs(value - fraction * clip_s) < 0.1 * clip_s, (value, fraction)
        page.wait_for_timeout(300)
        first, later = page.evaluate(
            "() => { const times = () => window.emogenStudy.clipTimes().slice(0, 10);"
            " const first = times(); const t0 = performance.now();"
            " while (performance.now() - t0 < 900) {} return [first, times()]; }"
        )
        assert first[position] == later[position] == value  # held there…
        pairs = [(a, b) for a, b in zip(first, later, strict=True) if a is not None]
        assert any(abs(a - b) > 0.05 for a, b in pairs)  # …the others play on
        held.append(tiles(page)[position])
        box = tile_box(page, position)
        crops.append(page.screenshot(clip=box))
    for a in range(4):
        for b in range(a + 1, 4):
            assert np.abs(held[a] - held[b]).mean() > 0.05, (a, b)  # four times, four frames
    pictures = [Image.open(BytesIO(c)).convert("RGB") for c in crops]
    side = min(p.height for p in pictures)
    sheet = Image.new("RGB", (4 * side, side + 24), "white")
    draw, font = ImageDraw.Draw(sheet), ImageFont.load_default(size=15)
    for k, (p, value) in enumerate(zip(pictures, values, strict=True)):
        sheet.paste(p.resize((side, side)), (k * side, 0))
        label = f"held at {value:.2f} s"
        draw.text((k * side + side // 2, side + 3), label, fill="black", font=font, anchor="mt")
    sheet.save(folder / name, optimize=True)
    times = replay_now(page)  # "Play all again": every tile from the start, the held one too
    assert len(times) == 10 and max(times) < 0.05, times
    assert page.input_value("#scrub") == "0"


def test_a_participant_evolves_moving_faces_on_a_desktop(
    example: tuple[ServerProcess, str], browser: Any, ict_model: Any
) -> None:
    server, db_url = example
    walk = open_walk(browser, server, "walker-desk", phone=False)
    page, folder = walk.page, pictures_folder()
    g = 0
    while walk.state["trial"]["status"] != "rating":  # every round of the first trial, on the page
        trial, generation, faces = walk.screen()
        assert (trial, generation) == (0, g)
        if g == 1:
            replay_now(page)
            page.wait_for_timeout(600)  # mid-clip
            page.screenshot(path=str(folder / "dynamic-walk-1366x768.png"))
            k = liveliest(faces)
            step_through(walk, k, folder, "dynamic-walk-scrub-1366x768.png")
            walk.touch(walk.face(k))  # taken back
        if g == 2:  # a reload mid-block: the same generation, the same clips
            walk.touch(walk.face(0))
            walk.reload()
            assert walk.screen() == (trial, generation, faces)
            marked = page.get_attribute("#grid > .cell:nth-child(1) .face", "aria-pressed")
            assert marked == "true"  # the tap made before the reload is kept
            walk.touch(walk.face(0))  # taken back
            times = clip_times(page)
            assert max(times) - min(times) < 0.02, times
        walk.choose(trial, generation, [f["id"] for f in faces])
        g += 1
    assert g == GENERATIONS + 1  # the whole evolution (generations 0-10) chosen on the page
    assert tomllib.loads(EXAMPLE.read_text())["ga"]["generations"] == GENERATIONS
    wait_ready(page, "rating")  # the face to rate, reached from the last round on the page, moves
    page.wait_for_function(
        "window.emogenStudy.clipTimes().some((t) => t !== null)", timeout=120_000
    )
    walk.rate(0, 5)
    # the rest of the session (three dynamic trials, then the static block) through the API
    walk.answer(until=lambda state: state["stage"] == "done")
    walk.reload()
    wait_ready(page, "done")
    assert page.inner_text("#done-code") == "DYNAMIC"
    page.screenshot(path=str(folder / "dynamic-walk-done-1366x768.png"))
    assert page.errors == [] and page.evaluate("window.__cspViolations") == []
    page.context.close()
    tables = check_records(walk, db_url, "walker-desk", ict_model, fallback=False)
    finals = tables["final_faces"]
    assert sorted(finals.trial) == list(range(8))
    # the curves of the face made on the page, for `emogen render clip` (docs/study.md)
    final = finals[finals.trial == 0].iloc[0]
    curves = tables["face_curves"]
    mine = curves[(curves.trial == 0) & (curves.generation == final.generation)
                  & (curves.face_id == final.face_id)]  # fmt: skip
    mine.to_csv(FINAL_CURVES, index=False)


def rows_of_tiles(page: Any) -> list[int]:
    """How many tiles each row of the grid holds, top to bottom."""
    tops = [round(tile_box(page, k)["y"]) for k in range(10)]
    return [tops.count(top) for top in sorted(set(tops))]


def test_a_participant_evolves_moving_faces_on_a_phone(
    example: tuple[ServerProcess, str], browser: Any, ict_model: Any
) -> None:
    server, db_url = example
    walk = open_walk(browser, server, "walker-phone", phone=True)
    page, folder = walk.page, pictures_folder()
    g = 0
    while walk.state["trial"]["status"] != "rating":  # every round of the first trial, on the page
        trial, generation, faces = walk.screen()
        assert (trial, generation) == (0, g)
        if g == 1:
            assert rows_of_tiles(page) == [2] * 5
            boxes = [tile_box(page, k) for k in range(10)]  # every face on the screen
            assert all(b["y"] + b["height"] <= 844 for b in boxes), boxes
            assert page.locator("#next").bounding_box()["y"] + 20 <= 844
            replay_now(page)
            page.wait_for_timeout(600)  # mid-clip
            page.screenshot(path=str(folder / "dynamic-walk-390x844.png"))
            k = liveliest(faces)
            step_through(walk, k, folder, "dynamic-walk-scrub-390x844.png")
            walk.touch(walk.face(k))  # taken back
        if g == 2:  # the phone turned: all ten play on, the choice made kept
            walk.touch(walk.face(8))
            page.set_viewport_size({"width": 844, "height": 390})
            page.wait_for_timeout(500)
            assert rows_of_tiles(page) == [5, 5]
            assert all(tile_box(page, k)["width"] >= 100 for k in range(10))
            times = clip_times(page)
            assert len(times) == 10 and max(times) - min(times) < 0.02, times
            moved = tiles_moving(page, want=5)  # all ten play on after the turn
            assert sum(m > 0.05 for m in moved) >= 5, moved
            page.screenshot(path=str(folder / "dynamic-walk-844x390.png"))
            assert page.get_attribute(".cell:nth-child(9) .face", "aria-pressed") == "true"
            page.set_viewport_size({"width": 390, "height": 844})
            page.wait_for_timeout(300)
            assert rows_of_tiles(page) == [2] * 5
            walk.touch(walk.face(8))  # taken back
        walk.choose(trial, generation, [f["id"] for f in faces])
        g += 1
    assert g == GENERATIONS + 1  # the whole evolution chosen on the phone's page
    wait_ready(page, "rating")
    page.wait_for_function(
        "window.emogenStudy.clipTimes().some((t) => t !== null)", timeout=120_000
    )
    walk.rate(0, 5)  # the evolved face rated with a tap
    wait_ready(page, "trial")
    assert page.errors == [] and page.evaluate("window.__cspViolations") == []
    page.context.close()
    check_records(walk, db_url, "walker-phone", ict_model, fallback=False)


def test_without_webgl_the_strips_play_and_the_records_say_so(
    example: tuple[ServerProcess, str], browser: Any, ict_model: Any
) -> None:
    """A browser that refuses WebGL: the page falls back to the server's images by itself; a
    moving face's image is the strip of its 11 frames, flipped in sync; every selection records
    that the server's images showed the faces (``fallback``: for a moving face, the strip)."""
    server, db_url = example
    walk = open_walk(browser, server, "walker-nogl", phone=False, script=NO_WEBGL)
    page = walk.page
    for g in range(2):
        trial, generation, faces = walk.screen()
        assert page.evaluate("window.emogenStudy.display") == "png"
        sizes = page.eval_on_selector_all(
            "#grid > .cell .slot img", "is => is.map((i) => [i.naturalWidth, i.naturalHeight])"
        )
        assert len(sizes) == 10 and all(w == 11 * h for w, h in sizes), sizes
        if g == 0:
            series = [tiles(page)]
            for _ in range(8):
                page.wait_for_timeout(250)
                series.append(tiles(page))
            moved = [max(np.abs(s[k] - series[0][k]).mean() for s in series[1:]) for k in range(10)]
            assert sum(m > 0.05 for m in moved) >= 8, moved
        walk.choose(trial, generation, [f["id"] for f in faces])
    assert page.errors == [] and page.evaluate("window.__cspViolations") == []
    page.context.close()
    check_records(walk, db_url, "walker-nogl", ict_model, fallback=True)
