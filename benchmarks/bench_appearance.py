"""Appearance: painting a skin atlas (fresh process, another appearance, cached) and what
textures cost a 512² face offscreen, against the flat look of EmoGen ≤ 0.2."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]

_COLD = """
import time, sys
t = time.perf_counter()
from emogen.model import load_model
m = load_model(sys.argv[1] if len(sys.argv) > 1 else None)
t1 = time.perf_counter()
from emogen.appearance import Appearance
from emogen.appearance.textures import skin_textures
skin_textures(m, Appearance(seed=11), irradiance=1.0)
print(time.perf_counter() - t1)
"""


def run(model: Any, model_path: str | None = None) -> dict[str, float]:  # type: ignore[no-untyped-def]
    from benchmarks.bench_render import _best
    from emogen.appearance import Appearance
    from emogen.appearance.identities import PRESETS
    from emogen.appearance.textures import skin_textures
    from emogen.render.renderer import Renderer

    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "EMOGEN_CACHE_DIR": tmp, "PYTHONPATH": str(REPO / "src")}
        out = subprocess.run(
            [sys.executable, "-c", _COLD, *([model_path] if model_path else [])],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
        cold = float(out.stdout.strip().splitlines()[-1])
        old = os.environ.get("EMOGEN_CACHE_DIR")
        os.environ["EMOGEN_CACHE_DIR"] = tmp
        try:
            skin_textures(model, Appearance(seed=1), irradiance=1.0)  # imports, detail tile
            warm = _best(lambda: skin_textures(model, Appearance(seed=2), irradiance=1.0), 1)
            cached = _best(lambda: skin_textures(model, Appearance(seed=2), irradiance=1.0), 3)
        finally:
            if old is None:
                os.environ.pop("EMOGEN_CACHE_DIR", None)
            else:
                os.environ["EMOGEN_CACHE_DIR"] = old

    w = model.rig.weights_from_names({"jawOpen": 0.3, "mouthSmile": 0.8, "browInnerUp": 0.6})[None]
    look = PRESETS["generic"].appearance
    times = {}
    for name, options in (
        ("flat, head framing (≤ 0.2)", {"framing": "head"}),
        ("flat, face framing", {}),
        ("textured, head framing", {"framing": "head", "appearance": look}),
        ("textured, face framing (default)", {"appearance": look}),
    ):
        with Renderer(model, size=512, **options) as r:  # type: ignore[arg-type]
            r.render(w)
            times[name] = _best(lambda r=r: r.render(w), 9)
    base = times["flat, head framing (≤ 0.2)"]
    print("\n== appearance (skin atlas 2048×1024 + detail tile, WebP) ==")
    print(f"paint + encode, fresh process  {cold:6.2f} s   (target ≤ 5; imports included)")
    print(f"another appearance             {warm:6.2f} s")
    print(f"cached                         {cached * 1000:6.1f} ms")
    print("one 512² face (best of 9):")
    for name, t in times.items():
        print(f"  {name:34s} {t * 1000:6.1f} ms   {t / base:4.2f}×")
    return {
        "paint_cold_s": cold,
        "paint_warm_s": warm,
        "cached_ms": cached * 1000,
        **{
            f"face512_{k}_ms": v * 1000
            for k, v in zip(
                ("flat_head", "flat_face", "tex_head", "tex_face"), times.values(), strict=True
            )
        },
    }


if __name__ == "__main__":
    sys.path[:0] = [str(REPO / "src"), str(REPO)]
    from emogen.model import load_model

    run(
        load_model(sys.argv[1] if len(sys.argv) > 1 else None),
        sys.argv[1] if len(sys.argv) > 1 else None,
    )
