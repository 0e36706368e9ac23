"""Pictures around rendered faces: footers, contact sheets, colour-bar legends and PNG files."""

from __future__ import annotations

import io
import json
from collections.abc import Sequence
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from emogen.errors import ConfigError, ShapeError
from emogen.render.look import default_look

try:  # Pillow comes with matplotlib, a core dependency
    from PIL import Image, ImageDraw, ImageFont, PngImagePlugin
except ImportError:  # pragma: no cover
    Image = None  # type: ignore[assignment]


def _pil() -> Any:
    if Image is None:  # pragma: no cover
        raise ConfigError("writing images needs Pillow: pip install Pillow")
    return Image


@cache
def _font_path() -> str | None:
    try:
        import matplotlib

        path = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
        return str(path) if path.is_file() else None
    except ImportError:  # pragma: no cover
        return None


@cache
def font(size: int) -> Any:
    """DejaVu Sans (shipped with matplotlib) at ``size`` pixels, so labels look the same everywhere."""
    _pil()
    path = _font_path()
    if path is not None:
        return ImageFont.truetype(path, size)
    return ImageFont.load_default(size)  # pragma: no cover


def _rgb255(srgb: Sequence[float]) -> tuple[int, int, int]:
    r, g, b = (round(255 * min(max(float(c), 0.0), 1.0)) for c in srgb)
    return r, g, b


def _text_colour(background: Sequence[float]) -> tuple[int, int, int]:
    return (20, 20, 20) if sum(background) / 3 > 0.45 else (235, 235, 235)


def add_footer(
    image: np.ndarray, text: str | None = None, *, background: Sequence[float] | None = None
) -> np.ndarray:
    """Append a strip with a small line of text (default: the ICT-FaceKit notice) below an image.

    image : (H, W, 3) uint8 → (H + strip, W, 3) uint8; the strip has the background colour.
    """
    bg = background if background is not None else default_look().background_srgb
    w = image.shape[1]
    size = max(9, min(14, w // 40))
    strip = _pil().new("RGB", (w, size + 8), _rgb255(bg))
    draw = ImageDraw.Draw(strip)
    label = _fit(draw, text if text is not None else default_look().footer, font(size), w - 4)
    draw.text((w // 2, size + 3), label, fill=_text_colour(bg), font=font(size), anchor="ms")
    return np.concatenate([np.asarray(image, dtype=np.uint8), np.asarray(strip)], axis=0)


def contact_sheet(
    images: np.ndarray,
    labels: Sequence[str] | None = None,
    *,
    columns: int = 5,
    footer: str | None = None,
    background: Sequence[float] | None = None,
    gap: int = 6,
) -> np.ndarray:
    """Tile images (n, H, W, 3) uint8 into a grid with a label under each and a footer line.

    footer None: the ICT-FaceKit notice; "" for none.
    """
    imgs = np.asarray(images)
    if imgs.ndim != 4 or imgs.shape[-1] != 3:
        raise ShapeError(f"images must have shape (n, height, width, 3); got {imgs.shape}")
    n, h, w = imgs.shape[:3]
    if labels is not None and len(labels) != n:
        raise ShapeError(f"labels must have one entry per image ({n}); got {len(labels)}")
    if columns < 1:
        raise ConfigError(f"columns must be at least 1; got {columns}")
    cols = min(columns, max(n, 1))
    rows = -(-n // cols)
    bg = background if background is not None else default_look().background_srgb
    label_size = max(10, min(18, w // 18))
    label_h = label_size + 8 if labels is not None else 0
    footer_text = default_look().footer if footer is None else footer
    footer_size = max(10, min(14, w // 22))
    footer_h = footer_size + 10 if footer_text else 0
    height = rows * (h + label_h) + (rows + 1) * gap + footer_h
    width = cols * w + (cols + 1) * gap
    sheet = _pil().new("RGB", (width, height), _rgb255(bg))
    draw = ImageDraw.Draw(sheet)
    ink = _text_colour(bg)
    for i in range(n):
        r, c = divmod(i, cols)
        x = gap + c * (w + gap)
        y = gap + r * (h + label_h + gap)
        sheet.paste(_pil().fromarray(np.ascontiguousarray(imgs[i])), (x, y))
        if labels is not None and labels[i]:
            text = _fit(draw, str(labels[i]), font(label_size), w)
            draw.text((x + w // 2, y + h + 4), text, fill=ink, font=font(label_size), anchor="mt")
    if footer_text:
        draw.text(
            (width // 2, height - 5), footer_text, fill=ink, font=font(footer_size), anchor="ms"
        )
    return np.asarray(sheet)


def _fit(draw: Any, text: str, fnt: Any, width: int) -> str:
    """Shorten ``text`` with an ellipsis until it fits ``width`` pixels."""
    if draw.textlength(text, font=fnt) <= width:
        return text
    while text and draw.textlength(text + "…", font=fnt) > width:
        text = text[:-1]
    return text + "…"


def colourbar(
    lut: np.ndarray,
    vmax: float,
    *,
    height: int,
    unit: str = "cm",
    background: Sequence[float] | None = None,
    title: str = "distance",
) -> np.ndarray:
    """A vertical colour-bar legend (height, W, 3) uint8 for ``lut (256, 3)`` sRGB in [0, 1]
    over ``[0, vmax]``, ticks at round numbers labelled in ``unit``."""
    bg = background if background is not None else default_look().background_srgb
    label_size = max(10, height // 34)
    bar_w, pad = max(12, height // 28), max(8, height // 40)
    top, bottom = pad + label_size + 6, height - pad
    values = tick_values(vmax)
    texts = [f"{v:g}" for v in values]
    heading = f"{title} ({unit})"
    text_w = max(int(font(label_size).getlength(t)) for t in texts) + 6
    text_w = max(text_w, int(font(label_size).getlength(heading)) - bar_w - 6)
    width = pad + bar_w + 6 + text_w + pad
    pil = _pil().new("RGB", (width, height), _rgb255(bg))
    draw = ImageDraw.Draw(pil)
    ink = _text_colour(bg)
    span = bottom - top
    rows = np.linspace(1.0, 0.0, span)  # top = vmax
    colours = (np.clip(lut[np.clip((rows * 255).round().astype(int), 0, 255)], 0, 1) * 255).round()
    bar = np.repeat(colours[:, None, :], bar_w, axis=1).astype(np.uint8)
    pil.paste(_pil().fromarray(bar), (pad, top))
    draw.rectangle([pad, top, pad + bar_w - 1, bottom - 1], outline=ink)
    for v, t in zip(values, texts, strict=True):
        y = bottom - 1 - round((span - 1) * v / vmax)
        draw.line([pad + bar_w, y, pad + bar_w + 4, y], fill=ink)
        draw.text((pad + bar_w + 6, y), t, fill=ink, font=font(label_size), anchor="lm")
    draw.text((pad, pad), heading, fill=ink, font=font(label_size), anchor="lt")
    return np.asarray(pil)


def tick_values(vmax: float, most: int = 6) -> list[float]:
    """Round tick values from 0 to at most ``vmax``: steps of 1, 2, 2.5 or 5 × 10^k."""
    if not vmax > 0:
        return [0.0]
    for k in range(-6, 7):
        for m in (1.0, 2.0, 2.5, 5.0):
            step = m * 10.0**k
            if vmax / step <= most - 1:
                n = int(np.floor(vmax / step + 1e-9))
                return [round(i * step, 10) for i in range(n + 1)]
    return [0.0, vmax]  # pragma: no cover


def png_bytes(image: np.ndarray, metadata: dict[str, Any] | None = None) -> bytes:
    """Encode (H, W, 3) uint8 as PNG; ``metadata`` goes into text chunks (dicts as JSON)."""
    info = PngImagePlugin.PngInfo() if Image is not None else None
    if info is not None:
        for key, value in (metadata or {}).items():
            info.add_text(key, value if isinstance(value, str) else json.dumps(value))
    buf = io.BytesIO()
    _pil().fromarray(np.ascontiguousarray(image)).save(
        buf, format="PNG", pnginfo=info, compress_level=3
    )
    return buf.getvalue()


def save_png(path: str | Path, image: np.ndarray, metadata: dict[str, Any] | None = None) -> Path:
    """Write (H, W, 3) uint8 as a PNG file (folders created); returns the path."""
    from emogen.render.errors import RenderError

    p = Path(path)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(png_bytes(image, metadata))
    except OSError as exc:
        raise RenderError(f"cannot write {p}: {exc.strerror}") from None
    return p


def read_png(path: str | Path) -> np.ndarray:
    """(H, W, 3) uint8 of a PNG file."""
    with _pil().open(path) as im:
        return np.asarray(im.convert("RGB"))


def oval_coverage(size: int, oval: tuple[float, float, float, float]) -> np.ndarray:
    """(size, size) float32 in [0, 1]: how much of each pixel lies inside the oval (centre x,
    centre y, radius x, radius y as fractions of the image, y down), its edge ramped over one
    pixel by the distance of the pixel's centre to the ellipse (first order)."""
    cx, cy, rx, ry = (v * size for v in oval)
    centres = np.arange(size, dtype=np.float64) + 0.5
    x = ((centres - cx) / rx)[None, :]
    y = ((centres - cy) / ry)[:, None]
    r = np.sqrt(x**2 + y**2)
    grad = np.sqrt((x / rx) ** 2 + (y / ry) ** 2) / np.maximum(r, 1e-12)
    return np.clip(0.5 - (r - 1) / np.maximum(grad, 1e-12), 0.0, 1.0).astype(np.float32)


def apply_oval(
    images: np.ndarray, oval: tuple[float, float, float, float], background: Sequence[float]
) -> np.ndarray:
    """Images (n, size, size, 3) uint8 seen through the oval on the background (sRGB)."""
    cover = oval_coverage(images.shape[1], oval)[None, :, :, None]
    bg = np.asarray(_rgb255(background), dtype=np.float32)
    out = images.astype(np.float32) * cover + bg * (1 - cover)
    return np.round(out).astype(np.uint8)
