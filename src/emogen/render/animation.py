"""A face that moves, as files: an animated WebP or GIF (Pillow) or an MP4 (H.264, through the
ffmpeg binary that the ``imageio-ffmpeg`` wheel carries: installed from PyPI with EmoGen,
nothing else to install). A frame sequence is PNGs (:func:`emogen.render.images.save_png`).

The WebP is lossless: its frames are the rendered pixels exactly. A GIF has at most 256
colours a frame (Pillow's quantiser); an MP4 is lossy (``-crf 18``, ``yuv420p`` for every
player). Frames are (n_frames, height, width, 3) uint8 sRGB, shown ``1/fps`` seconds each,
looped forever (WebP, GIF; an MP4 plays once). In a WebP or GIF, identical frames in a row
(the face at rest) are stored once and shown for their summed time (Pillow), so the file plays
the same frames at the same times.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from emogen.errors import ConfigError, ShapeError

#: The animated formats, by file suffix.
FORMATS = (".webp", ".gif", ".mp4")


def animation_format(path: Path, option: str = "--out") -> str:
    """The format of an animation file by its suffix (one of :data:`FORMATS`, lower case)."""
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise ConfigError(
            f"{option} {path}: an animation is a {', '.join(FORMATS)} file (or a folder for "
            f"the frames as PNGs); got the suffix {path.suffix or '(none)'!r}"
        )
    return suffix


def write_animation(path: Path, frames: np.ndarray, fps: float, *, comment: str = "") -> Path:
    """Write ``frames`` (n, H, W, 3) uint8 at ``fps`` to ``path`` (its suffix: the format);
    ``comment``: a line of text stored in the file (WebP/GIF: its comment or XMP; MP4: the
    ``comment`` tag). Returns the path."""
    from emogen.render.errors import RenderError

    kind = animation_format(path)
    f = np.asarray(frames)
    if f.ndim != 4 or f.shape[-1] != 3 or f.dtype != np.uint8 or len(f) == 0:
        raise ShapeError(
            f"frames must be (n_frames, height, width, 3) uint8, n_frames ≥ 1; got {f.shape} "
            f"{f.dtype}"
        )
    if not 1 <= fps <= 240:
        raise ConfigError(f"fps must be in [1, 240]; got {fps}")
    # written beside it, then renamed: a failed write leaves no partial file and an earlier
    # file of that name as it was
    partial = path.with_name(f".{path.stem}.partial-{os.getpid()}{kind}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if kind == ".mp4":
            _write_mp4(partial, f, fps, comment)
        else:
            _write_pillow(partial, f, fps, kind, comment)
        os.replace(partial, path)
    except OSError as exc:
        raise RenderError(f"cannot write {path}: {exc}") from exc
    finally:
        partial.unlink(missing_ok=True)
    return path


def _write_pillow(path: Path, frames: np.ndarray, fps: float, kind: str, comment: str) -> None:
    from PIL import Image

    images = [Image.fromarray(frame) for frame in frames]
    duration = round(1000 / fps)  # ms a frame: both formats count whole milliseconds
    options: dict[str, Any] = {"save_all": True, "append_images": images[1:], "loop": 0}
    if kind == ".webp":
        # lossless: the pixels are the same at any effort; quality 50, method 2 encodes a
        # report's 25-frame 810×178 grid in 0.31 s of CPU where 100, 4 took 3.3 s, for a file
        # 6 % larger (685 against 648 kB)
        options |= {"lossless": True, "quality": 50, "method": 2}
        if comment:
            options["xmp"] = comment.encode()
    else:
        options |= {"optimize": False, "disposal": 1}
        if comment:
            options["comment"] = comment.encode()
    images[0].save(path, duration=duration, **options)


def _write_mp4(path: Path, frames: np.ndarray, fps: float, comment: str) -> None:
    import imageio_ffmpeg

    _, height, width, _ = frames.shape
    if height % 2 or width % 2:
        raise ConfigError(
            f"an MP4's frames need an even width and height (H.264, yuv420p); got "
            f"{width}×{height}: give an even --size"
        )
    params = ["-crf", "18", "-preset", "medium", "-threads", "1"]
    if comment:
        params += ["-metadata", f"comment={comment}"]
    writer = imageio_ffmpeg.write_frames(
        str(path),
        (width, height),
        fps=fps,
        codec="libx264",
        pix_fmt_in="rgb24",
        pix_fmt_out="yuv420p",
        quality=None,
        macro_block_size=1,
        ffmpeg_log_level="error",
        output_params=params,
    )
    writer.send(None)  # start ffmpeg
    try:
        for frame in frames:
            writer.send(np.ascontiguousarray(frame))
    finally:
        writer.close()


def read_animation(path: Path) -> tuple[np.ndarray, list[float]]:
    """The frames (n, H, W, 3) uint8 of an animated WebP or GIF and each frame's duration
    (ms), as Pillow decodes them (for tests and for looking at a file's frames)."""
    from PIL import Image, ImageSequence

    with Image.open(path) as im:
        frames, durations = [], []
        for frame in ImageSequence.Iterator(im):
            frames.append(np.asarray(frame.convert("RGB")))
            durations.append(float(frame.info.get("duration", 0)))
    return np.stack(frames), durations
