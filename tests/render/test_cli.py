"""`emogen render …` through Typer, on a local app holding only the render sub-app."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import typer
from PIL import Image
from typer.testing import CliRunner

from emogen.appearance.identities import PRESETS
from emogen.appearance.params import GENERATOR_VERSION, Appearance
from emogen.cli.render import render_app
from emogen.render.images import read_png

app = typer.Typer()
app.add_typer(render_app, name="render")


@app.callback()
def _root() -> None:
    """Test root."""


runner = CliRunner()


@pytest.fixture
def model_args(ict_dir: Path) -> list[str]:
    return ["--model", str(ict_dir)]


def run(*args: str) -> str:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, result.output
    return result.output


def test_render_one_face_writes_a_512_png(tmp_path: Path, model_args: list[str]) -> None:
    out = tmp_path / "a.png"
    assert "wrote" in run("render", "--weight", "jawOpen=1", "--out", str(out), *model_args)
    image = read_png(out)
    assert image.shape == (512, 512, 3)
    with Image.open(out) as im:
        record = json.loads(im.text["emogen"])
        assert record["weights"] == {"jawOpen": 1.0} and "ICT" in im.text["Copyright"]


def test_render_rows_of_a_csv_with_options(tmp_path: Path, model_args: list[str]) -> None:
    csv = tmp_path / "faces.csv"
    csv.write_text("label,jawOpen\nclosed,0\nopen,1\n")
    run(
        "render",
        "--weights",
        str(csv),
        "--weight",
        "eyeBlink=1",
        "--out",
        str(tmp_path / "f"),
        "--size",
        "96",
        "--background",
        "white",
        "--identity",
        "female",
        "--footer",
        *model_args,
    )
    files = sorted((tmp_path / "f").glob("*.png"))
    assert [f.name for f in files] == ["face_000.png", "face_001.png"]
    image = read_png(files[1])
    assert image.shape[1] == 96 and image.shape[0] > 96  # footer strip
    assert tuple(image[0, 0]) == (255, 255, 255)
    run(
        "render",
        "--weights",
        str(csv),
        "--out",
        str(tmp_path / "g_{label}.png"),
        "--size",
        "32",
        *model_args,
    )
    assert (tmp_path / "g_open.png").is_file()


def test_sheet_and_heatmap(tmp_path: Path, model_args: list[str]) -> None:
    sheet = tmp_path / "sheet.png"
    run(
        "render",
        "sheet",
        "--face",
        "neutral",
        "--face",
        "jawOpen=1,mouthFunnel=0.5",
        "--face",
        "mouthSmile=1",
        "--size",
        "64",
        "--columns",
        "2",
        "--out",
        str(sheet),
        *model_args,
    )
    image = read_png(sheet)
    assert image.shape[1] == 2 * 64 + 3 * 6 and image.shape[0] > 2 * 64
    heat = tmp_path / "heat.png"
    output = run(
        "render",
        "heatmap",
        "--weight",
        "jawOpen=1",
        "--reference-weight",
        "jawOpen=0.5",
        "--size",
        "96",
        "--out",
        str(heat),
        *model_args,
    )
    assert "largest distance" in output and read_png(heat).shape[1] > 96


def test_errors_are_one_line(tmp_path: Path, model_args: list[str]) -> None:
    cases = [
        (["render", "--weight", "jawOpen=1"], "--out is required"),
        (
            ["render", "--weight", "nope=1", "--out", str(tmp_path / "x.png")],
            "unknown shape or gene 'nope'",
        ),
        (["render", "--weight", "jawOpen", "--out", str(tmp_path / "x.png")], "NAME=VALUE"),
        (["render", "sheet", "--out", str(tmp_path / "s.png")], "--face"),
        (
            ["render", "--background", "purplish", "--out", str(tmp_path / "x.png")],
            "background must be",
        ),
    ]
    csv = tmp_path / "two.csv"
    csv.write_text("jawOpen\n0\n1\n")
    cases.append((["render", "--weights", str(csv), "--out", str(tmp_path / "x.png")], "pattern"))
    csv3 = tmp_path / "three.csv"
    csv3.write_text("jawOpen\n0\n1\n0.5\n")
    cases.append(
        (["render", "heatmap", "--weights", str(csv3), "--out", str(tmp_path / "h.png")], "2 rows")
    )
    for args, message in cases:
        result = runner.invoke(app, [*args, *model_args])
        assert result.exit_code == 2, (args, result.output)
        assert message in result.output and "Traceback" not in result.output
    assert not list(tmp_path.glob("x.png"))


def test_identities_render_with_their_appearance(tmp_path: Path, model_args: list[str]) -> None:
    """Each preset draws its own skin (not only its shape); --plain draws the flat look; the
    PNG records everything needed to render it again."""
    common = ["--weight", "mouthSmile_L=0.6", "--size", "96", *model_args]
    paths = {}
    for name, extra in [
        ("male-dark", []),
        ("female-light", []),
        ("male-dark-plain", ["--plain"]),
        ("male-dark-head", ["--framing", "head"]),
    ]:
        paths[name] = tmp_path / f"{name}.png"
        identity = "female-light" if name == "female-light" else "male-dark"
        run("render", "--identity", identity, *extra, "--out", str(paths[name]), *common)
    images = {k: read_png(p).astype(int) for k, p in paths.items()}

    def differ(a: str, b: str) -> float:
        return float(np.abs(images[a] - images[b]).mean())

    assert differ("male-dark", "female-light") > 10
    assert differ("male-dark", "male-dark-plain") > 10
    assert differ("male-dark", "male-dark-head") > 5
    # dark skin is darker than light skin in the middle of the face
    mid = (slice(40, 56), slice(40, 56))
    assert images["male-dark"][mid].mean() < images["female-light"][mid].mean() - 40
    with Image.open(paths["male-dark"]) as im:
        record = json.loads(im.text["emogen"])
    assert record["identity"] == "male-dark" and record["shape"] == "male"
    assert Appearance(**record["appearance"]) == PRESETS["male-dark"].appearance
    assert record["appearance_generator"] == GENERATOR_VERSION and record["framing"] == "face"
    with Image.open(paths["male-dark-plain"]) as im:
        assert json.loads(im.text["emogen"])["appearance"] is None


def test_unknown_identity_exits_and_writes_nothing(tmp_path: Path, model_args: list[str]) -> None:
    out = tmp_path / "x.png"
    for args in (["--out", str(out)], ["sheet", "--face", "neutral", "--out", str(out)]):
        result = runner.invoke(app, ["render", *args, "--identity", "femal-light", *model_args])
        assert result.exit_code == 2, result.output
        lines = result.output.strip().splitlines()
        assert len(lines) == 1 and "unknown identity 'femal-light'" in lines[0]
        assert "female-light" in lines[0] and "male-dark" in lines[0] and "generic" in lines[0]
    assert not list(tmp_path.iterdir())
