"""The compiled cache: same arrays as a cold parse; any source change invalidates it."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

import emogen
from emogen.model.io import cache
from emogen.model.io.ict import load_ict_folder


def test_warm_load_equals_cold_parse(tiny_dir: Path) -> None:
    cold = load_ict_folder(tiny_dir)
    assert cache.load_cached(tiny_dir) is None
    cache.store(tiny_dir, cold)
    warm = cache.load_cached(tiny_dir)
    assert warm is not None
    np.testing.assert_array_equal(warm.deltas, cold.deltas)
    np.testing.assert_array_equal(warm.topology.polygons, cold.topology.polygons)
    assert warm.shape_names == cold.shape_names and warm.model_hash == cold.model_hash


def test_changed_file_invalidates(tiny_dir: Path) -> None:
    rig = tiny_dir.parent / "tiny_rig.toml"
    first = emogen.load_model(tiny_dir, rig=rig)
    path = tiny_dir / "jawOpen.obj"
    text = path.read_text()
    lines = text.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("v "))
    lines[i] = "v 9.000000 9.000000 9.000000"
    path.write_text("\n".join(lines) + "\n")
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 10_000_000))
    second = emogen.load_model(tiny_dir, rig=rig)
    assert second.model_hash != first.model_hash
    w = np.zeros((1, second.n_shapes))
    w[0, second.shape_index("jawOpen")] = 1
    np.testing.assert_allclose(second.evaluate(w)[0, 0], [9, 9, 9], atol=1e-5)


def test_corrupt_cache_is_ignored(tiny_dir: Path) -> None:
    rig = tiny_dir.parent / "tiny_rig.toml"
    emogen.load_model(tiny_dir, rig=rig)
    for f in (cache.cache_root() / "compiled").glob("model-*.npz"):
        f.write_bytes(b"garbage")
    again = emogen.load_model(tiny_dir, rig=rig)
    assert again.n_vertices == 5
