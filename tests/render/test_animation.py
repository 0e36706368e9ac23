"""Animation writers: a lossless WebP holds the frames exactly, a GIF holds every frame with its
duration (256 colours), an MP4 decodes (by ffmpeg itself, through imageio-ffmpeg) to the frames
within H.264's loss; a bad name or size is refused by name."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from emogen.errors import ConfigError
from emogen.render.animation import read_animation, write_animation


def frames(n: int = 6, size: int = 32) -> np.ndarray:
    """A moving square on a grey ground: each frame differs from the one before."""
    out = np.full((n, size, size, 3), 128, dtype=np.uint8)
    for i in range(n):
        out[i, 4:14, 2 + 3 * i : 12 + 3 * i] = (200, 40, 30)
    return out


def test_webp_is_lossless_and_keeps_every_frame(tmp_path: Path) -> None:
    f = frames()
    path = write_animation(tmp_path / "a.webp", f, 25)
    got, durations = read_animation(path)
    np.testing.assert_array_equal(got, f)
    assert durations == [40.0] * len(f)


def test_gif_keeps_every_frame_and_its_time(tmp_path: Path) -> None:
    f = frames()  # three colours: a GIF's palette holds them exactly
    got, durations = read_animation(write_animation(tmp_path / "a.gif", f, 20))
    np.testing.assert_array_equal(got, f)
    assert durations == [50.0] * len(f)


def test_mp4_decodes_to_the_frames(tmp_path: Path) -> None:
    import imageio_ffmpeg

    f = frames(n=12, size=64)
    path = write_animation(tmp_path / "a.mp4", f, 30)
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = reader.__next__()
    assert tuple(meta["size"]) == (64, 64) and meta["fps"] == 30
    got = np.stack([np.frombuffer(b, np.uint8).reshape(64, 64, 3) for b in reader])
    assert len(got) == len(f)
    assert np.abs(got.astype(int) - f.astype(int)).mean() < 3  # lossy, but the same pictures
    moved = np.abs(got[-1].astype(int) - got[0].astype(int)).mean()
    truth = np.abs(f[-1].astype(int) - f[0].astype(int)).mean()
    assert abs(moved - truth) < 0.2 * truth  # and it moves as the frames do


@pytest.mark.parametrize(
    ("name", "data", "message"),
    [
        ("a.avi", frames(), r"\.webp, \.gif, \.mp4 file.*got the suffix '\.avi'"),
        ("a.mp4", frames(size=33), r"even width and height.*33×33"),
        ("a.webp", frames()[..., :2], r"frames must be \(n_frames, height, width, 3\)"),
    ],
)
def test_bad_files_are_refused_by_name(
    tmp_path: Path, name: str, data: np.ndarray, message: str
) -> None:
    with pytest.raises((ConfigError, ValueError), match=message):
        write_animation(tmp_path / name, data, 30)
    assert not (tmp_path / name).exists()
