"""Error heatmaps, contact sheets, legends, footers, PNG files and weight CSVs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from emogen.errors import ConfigError, DataError, ShapeError
from emogen.render.distance_map import colour_lut, nice_ceiling, render_heatmap, vertex_distances
from emogen.render.images import (
    add_footer,
    colourbar,
    contact_sheet,
    png_bytes,
    read_png,
    save_png,
    tick_values,
)
from emogen.render.renderer import Renderer
from emogen.render.weights import describe, read_weights_csv


def test_vertex_distances_against_a_plain_loop() -> None:
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(2, 5, 7, 3))
    d = vertex_distances(a, b[0])
    for i in range(2):
        for j in range(7):
            assert d[i, j] == pytest.approx(float(np.sqrt(((a[i, j] - b[0, j]) ** 2).sum())))
    with pytest.raises(ShapeError):
        vertex_distances(a, b[0, :3])


@pytest.mark.parametrize(
    ("x", "up"), [(0.37, 0.4), (2.519, 3.0), (4.2, 5.0), (10.0, 10.0), (0.0, 1.0)]
)
def test_nice_ceiling(x: float, up: float) -> None:
    assert nice_ceiling(x) == pytest.approx(up)


def test_tick_values_are_round() -> None:
    assert tick_values(5.0) == [0, 1, 2, 3, 4, 5]
    assert tick_values(0.4) == pytest.approx([0, 0.1, 0.2, 0.3, 0.4])
    assert tick_values(2.5) == pytest.approx([0, 0.5, 1.0, 1.5, 2.0, 2.5])


def test_heatmap_colours_by_distance(small_renderer: Renderer, ict_model) -> None:  # type: ignore[no-untyped-def]
    w = np.stack([ict_model.rig.weights_from_names({"jawOpen": x}) for x in (1.0, 0.0)])
    a, b = ict_model.evaluate(w)
    heat = render_heatmap(small_renderer, a, b)  # viridis by default
    assert heat.max_distance == pytest.approx(vertex_distances(a, b).max(), rel=1e-6)
    assert heat.vmax >= heat.max_distance
    h, w_ = heat.image.shape[:2]
    assert h > 128 and w_ > 128  # face + legend + footer strip
    # the forehead (distance 0) takes the colour map's bottom colour (viridis: dark violet)
    top = (colour_lut("viridis")[0] * 255).round()
    face = heat.image[:128, :128].astype(int)
    forehead = face[25:35, 55:73].reshape(-1, 3).mean(0)
    assert forehead[2] > forehead[0] and np.abs(forehead - top).max() < 60
    with pytest.raises(ConfigError, match="colour map"):
        render_heatmap(small_renderer, a, b, cmap="no-such-map")
    for rainbow in ("turbo", "jet", "rainbow_r"):  # not perceptual: refused for magnitudes
        with pytest.raises(ConfigError, match=f"'{rainbow}' is not perceptually uniform"):
            render_heatmap(small_renderer, a, b, cmap=rainbow)
    with pytest.raises(ConfigError, match="vmax"):
        render_heatmap(small_renderer, a, b, vmax=-1.0)


def test_contact_sheet_layout_and_errors() -> None:
    imgs = np.zeros((7, 40, 30, 3), np.uint8)
    sheet = contact_sheet(imgs, [f"face {i}" for i in range(7)], columns=3, footer="notice")
    assert sheet.shape[1] == 3 * 30 + 4 * 6 and sheet.shape[0] > 3 * 40
    plain = contact_sheet(imgs, None, columns=7, footer="")
    assert plain.shape == (40 + 12, 7 * 30 + 8 * 6, 3)
    with pytest.raises(ShapeError, match="labels"):
        contact_sheet(imgs, ["a"])
    with pytest.raises(ConfigError, match="columns"):
        contact_sheet(imgs, columns=0)


def test_footer_strip_and_legend() -> None:
    image = np.full((64, 200, 3), 128, np.uint8)
    out = add_footer(image)
    assert out.shape[0] > 64 and np.array_equal(out[:64], image)
    assert (out[64:] != 128).any()  # the notice is written
    bar = colourbar(colour_lut("viridis"), 2.0, height=200)
    assert bar.shape[0] == 200 and bar.shape[1] > 20


def test_png_round_trip_with_metadata(tmp_path: Path) -> None:
    image = np.random.default_rng(0).integers(0, 255, (9, 11, 3), dtype=np.uint8)
    path = save_png(tmp_path / "sub" / "x.png", image, {"emogen": {"a": 1}, "Copyright": "c"})
    assert np.array_equal(read_png(path), image)
    with Image.open(path) as im:
        assert im.text["Copyright"] == "c" and im.text["emogen"] == '{"a": 1}'
    assert png_bytes(image)[:8] == b"\x89PNG\r\n\x1a\n"


def test_weights_csv(tmp_path: Path, ict_model) -> None:  # type: ignore[no-untyped-def]
    csv = tmp_path / "faces.csv"
    csv.write_text("label,jawOpen,mouthSmile_L,mouthSmile\nopen,1,,\n,0.5,0.2,0.7\n")
    w, labels = read_weights_csv(csv, ict_model.rig)
    idx = ict_model.shape_index
    assert w.shape == (2, ict_model.n_shapes)
    assert w[0, idx("jawOpen")] == 1 and w[1, idx("mouthSmile_R")] == 0.7
    assert labels[0] == "open" and labels[1].startswith("mouthSmile .7")
    csv.write_text("jawOpen\nlots\n")
    with pytest.raises(ConfigError, match=r"line 2.*not a number"):
        read_weights_csv(csv, ict_model.rig)
    csv.write_text("jawOpen\n2\n")
    with pytest.raises(ConfigError, match=r"line 2.*\[0, 1\]"):
        read_weights_csv(csv, ict_model.rig)
    csv.write_text("jawOpen,bogus\n1,1\n")
    with pytest.raises(DataError, match="unknown column 'bogus'"):
        read_weights_csv(csv, ict_model.rig)
    csv.write_text("jawOpen\n")
    with pytest.raises(ConfigError, match="no faces"):
        read_weights_csv(csv, ict_model.rig)
    assert describe({}) == "neutral"
    assert describe({"a": 1, "b": 0.5, "c": 0.25, "d": 0.1}) == "a 1, b .5, c .25 …"
