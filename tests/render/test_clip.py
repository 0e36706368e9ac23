"""`emogen render clip`: a face that moves, from a face_curves CSV, to frames, a lossless WebP
and a sheet of key frames. Each frame is the face of docs/ga.md's curve formula (written here as
a plain loop) at k / fps, rendered as a still face; the same clip rendered twice gives the same
pixels within the golden images' tolerance; bad input is refused by name."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import typer
from PIL import Image
from typer.testing import CliRunner

from emogen.cli.render import render_app
from emogen.render.animation import read_animation
from emogen.render.images import read_png
from tests.ga.test_genome import curve_loop
from tests.render.test_golden import MAX_FRACTION_OFF, MAX_MEAN_ABS, compare

app = typer.Typer()
app.add_typer(render_app, name="render")


@app.callback()
def _root() -> None:
    """Test root."""


runner = CliRunner()
#: gene: amplitude, onset, acceleration, peak, deceleration, offset (a surprise, planted)
CURVES = {
    "browInnerUp": (0.9, 0.05, 0.3, 0.15, 0.2, 0.55),
    "eyeWide": (0.75, 0.02, 0.6, 0.1, 0.1, 0.5),
    "jawOpen": (0.5, 0.12, 0.2, 0.2, 0.1, 0.5),
}
FPS, SIZE = 8, 96


def write_curves(path: Path, curves: dict[str, tuple[float, ...]], **extra: object) -> Path:
    head = "gene,amplitude,onset,acceleration,peak,deceleration,offset"
    lines = [head + "".join(f",{k}" for k in extra)]
    lines += [",".join([g, *map(str, v), *map(str, extra.values())]) for g, v in curves.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


def reference_weight(gene: tuple[float, ...], t: float) -> float:
    """docs/ga.md's curve, one number at a time (tests/ga/test_genome.py's plain loop)."""
    return gene[0] * curve_loop(list(gene[1:]), t)


def clip(*args: str) -> str:
    result = runner.invoke(app, ["render", "clip", *args])
    assert result.exit_code == 0, result.output
    return result.output


def test_frames_are_the_curves_faces_and_the_same_every_time(tmp_path: Path, ict_dir: Path) -> None:
    curves = write_curves(tmp_path / "c.csv", CURVES)
    common = ["--model", str(ict_dir), "--size", str(SIZE), "--fps", str(FPS), "--no-hold"]
    out = clip(str(curves), "--out", str(tmp_path / "a"), "--out", str(tmp_path / "a.webp"),
               "--sheet", str(tmp_path / "s.png"), *common)  # fmt: skip
    clip(str(curves), "--out", str(tmp_path / "b"), *common)
    n = int(np.ceil(1.25 * FPS)) + 1  # 0, 1/8, …, the first frame at or after the clip's end
    assert f"{n} frames at 8/s" in out
    a = [read_png(tmp_path / "a" / f"frame_{k:04d}.png") for k in range(n)]
    b = [read_png(tmp_path / "b" / f"frame_{k:04d}.png") for k in range(n)]
    for x, y in zip(a, b, strict=True):  # the same clip twice: the same pixels
        mean_abs, off = compare(x, y)
        assert mean_abs < MAX_MEAN_ABS and off < MAX_FRACTION_OFF
    # lossless, every frame shown 1/8 s (identical frames in a row, the face at rest, are
    # stored once, shown for their summed time)
    webp, durations = read_animation(tmp_path / "a.webp")
    shown = np.repeat(webp, [round(d / 125.0) for d in durations], axis=0)
    np.testing.assert_array_equal(shown, np.stack(a))
    # each frame is the still face (`emogen render --weights`) of the documented formula at k / fps
    times = [0.25, 0.5, 1.25]
    rows = [[f"{reference_weight(v, t):.17g}" for v in CURVES.values()] for t in times]
    table = "\n".join([",".join(CURVES), *(",".join(r) for r in rows)]) + "\n"
    (tmp_path / "w.csv").write_text(table)
    runner.invoke(app, ["render", "--weights", str(tmp_path / "w.csv"), "--out",
                        str(tmp_path / "ref"), "--model", str(ict_dir), "--size", str(SIZE)])  # fmt: skip
    for k, t in enumerate(times):
        reference = read_png(tmp_path / "ref" / f"face_{k:03d}.png")
        mean_abs, off = compare(a[round(t * FPS)], reference)
        assert mean_abs < MAX_MEAN_ABS and off < MAX_FRACTION_OFF, (t, mean_abs, off)
    assert compare(a[4], a[0])[0] > 3 * MAX_MEAN_ABS  # mid-clip is not the face at rest
    with Image.open(tmp_path / "a" / "frame_0002.png") as im:
        record = json.loads(im.text["emogen"])
    assert record["time_s"] == 0.25 and record["clip"]["clip_s"] == 1.25
    sheet = read_png(tmp_path / "s.png")
    assert sheet.shape[1] > 5 * SIZE  # 11 key frames, six a row


@pytest.mark.parametrize(
    ("curves", "extra", "args", "message"),
    [
        ({"jawOpn": CURVES["jawOpen"]}, {}, [], "gene 'jawOpn' is not a gene.*did you mean 'jawOpen'"),
        ({"jawOpen": (0.5, 1.4, 0, 0, 0, 0)}, {}, [], r"jawOpen.*onset must be a number in \[0, 1\]; got 1.4"),
        (CURVES, {"face_id": 3}, ["--select", "face_idd=3"], "--select 'face_idd=3'.*face_id"),
        (CURVES, {"face_id": 3}, ["--select", "face_id=4"], "no row .* face_id = 4"),
        (CURVES, {"clip_s": 1.25, "onset_s": 0.1, "peak_s": 0.3, "offset_s": 0.9}, [],
         "onset_s/peak_s/offset_s are not its curves'"),
        (CURVES, {}, ["--fps", "0.5"], r"--fps must be in \[1, 240\]; got 0.5"),
    ],
)  # fmt: skip
def test_bad_input_is_refused_by_name(
    tmp_path: Path, ict_dir: Path, curves: dict, extra: dict, args: list[str], message: str
) -> None:
    path = write_curves(tmp_path / "c.csv", curves, **extra)
    result = runner.invoke(
        app, ["render", "clip", str(path), "--out", str(tmp_path / "a.webp"),
              "--model", str(ict_dir), *args],
    )  # fmt: skip
    assert result.exit_code != 0
    assert __import__("re").search(message, " ".join(result.output.split())), result.output
    assert not (tmp_path / "a.webp").exists()


def test_two_faces_need_a_select(tmp_path: Path, ict_dir: Path) -> None:
    path = tmp_path / "c.csv"
    one = write_curves(tmp_path / "one.csv", CURVES, face_id=1).read_text().splitlines()
    two = write_curves(tmp_path / "two.csv", CURVES, face_id=2).read_text().splitlines()
    path.write_text("\n".join(one + two[1:]) + "\n")
    result = runner.invoke(app, ["render", "clip", str(path), "--out", str(tmp_path / "a.gif"),
                                 "--model", str(ict_dir)])  # fmt: skip
    assert (
        result.exit_code != 0 and "holds 2 faces" in result.output and "--select" in result.output
    )
