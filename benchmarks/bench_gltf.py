"""GLB export: time, bytes raw and on the wire (gzip -9)."""

from __future__ import annotations

import gzip
import tempfile
import time
from pathlib import Path


def run(model) -> dict[str, float]:  # type: ignore[no-untyped-def]
    from emogen.render.model_glb import export_model_glb

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "face.glb"
        t = time.perf_counter()
        export_model_glb(model, path)
        seconds = time.perf_counter() - t
        raw = path.read_bytes()
    wire = len(gzip.compress(raw, 9))
    print("\n== browser GLB (morph targets: positions + normals, visible parts) ==")
    print(
        f"export {seconds:.2f} s   raw {len(raw) / 1e6:.2f} MB   on the wire (gzip -9) {wire / 1e6:.2f} MB"
    )
    return {"export_s": seconds, "raw_bytes": len(raw), "gzip_bytes": wire}
