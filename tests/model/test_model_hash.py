"""The model hash covers everything that shapes a stimulus, and an ICT-FaceKit folder is checked
against the pinned manifest; records carrying the older (geometry-only) hash still match."""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import emogen
from emogen.errors import ModelFileError
from emogen.model.io.ict import ALLOW_MODIFIED_ENV, load_ict_folder, model_content_hash
from emogen.model.model_hash import stimulus_hash
from emogen.model.regions import ict_regions


def _cut_copy(ict_dir: Path, tmp_path: Path) -> tuple[Path, int, int]:
    """The model folder (links) with a neutral mesh cut half way through its face lines."""
    folder = tmp_path / "FaceXModel"
    folder.mkdir()
    for p in ict_dir.iterdir():
        if p.name != "generic_neutral_mesh.obj":
            (folder / p.name).symlink_to(p)
    lines = (ict_dir / "generic_neutral_mesh.obj").read_bytes().splitlines(keepends=True)
    faces = [i for i, line in enumerate(lines) if line.startswith(b"f ")]
    keep = faces[len(faces) // 2]
    (folder / "generic_neutral_mesh.obj").write_bytes(b"".join(lines[:keep]))
    return folder, len(faces), len(faces[: len(faces) // 2])


def test_a_cut_neutral_mesh_is_named_against_the_pinned_manifest(
    ict_dir: Path, ict_model, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder, n_all, n_kept = _cut_copy(ict_dir, tmp_path)
    monkeypatch.delenv(ALLOW_MODIFIED_ENV, raising=False)
    with pytest.raises(ModelFileError) as info:
        emogen.load_model(folder, use_cache=False)
    message = str(info.value)
    assert "differs from the pinned ICT-FaceKit files" in message
    manifest = json.loads((Path(emogen.__file__).parent / "data" / "ict_manifest.json").read_text())
    pinned = {Path(f["path"]).name: f for f in manifest["files"]}
    size = (folder / "generic_neutral_mesh.obj").stat().st_size
    expected = f"generic_neutral_mesh.obj ({size} bytes, pinned "
    assert expected + f"{pinned['generic_neutral_mesh.obj']['size']})" in message
    assert "in 1 file(s)" in message  # the linked, untouched files match

    # changed on purpose: it loads, but its hash is not the real model's (the old hash was)
    monkeypatch.setenv(ALLOW_MODIFIED_ENV, "1")
    cut = emogen.load_model(folder, use_cache=False)
    assert len(cut.polygons) == n_kept < n_all == len(ict_model.polygons)
    assert cut.legacy_model_hash == ict_model.legacy_model_hash  # the version-1 blind spot
    assert cut.model_hash != ict_model.model_hash
    assert not cut.hash_matches(ict_model.model_hash)


def test_the_real_model_matches_the_manifest_and_its_recorded_hashes(ict_model) -> None:
    assert ict_model.model_hash != ict_model.legacy_model_hash
    assert ict_model.hash_matches(ict_model.model_hash)
    assert not ict_model.hash_matches(ict_model.legacy_model_hash)  # only a study's replay
    assert not ict_model.hash_matches("") and not ict_model.hash_matches("0" * 64)
    # the legacy hash is the geometry hash as defined before: recomputed independently here
    h = hashlib.sha256()
    h.update(
        f"{ict_model.name}\n{ict_model.n_vertices}\n{','.join(ict_model.shape_names)}\n".encode()
    )
    h.update(np.ascontiguousarray(ict_model.base_neutral, dtype=np.float32).tobytes())
    h.update(np.ascontiguousarray(ict_model.deltas, dtype=np.float32).tobytes())
    assert ict_model.legacy_model_hash == h.hexdigest()


def test_every_part_of_a_stimulus_changes_the_hash(tiny_dir: Path) -> None:
    model = emogen.load_model(tiny_dir, rig=tiny_dir.parent / "tiny_rig.toml")
    arrays = load_ict_folder(tiny_dir)
    rig, regions = model.rig, model.regions
    base = stimulus_hash(arrays, rig, regions)
    assert base == model.model_hash
    topo = arrays.topology
    uvs = topo.uvs.copy()
    uvs[0, 0] += 0.25
    variants = {
        "uvs": replace(arrays, topology=replace(topo, uvs=uvs)),
        "polygons": replace(arrays, topology=replace(topo, polygons=topo.polygons[:1])),
        "materials": replace(arrays, topology=replace(topo, materials=("M_Other",))),
        "identities": replace(arrays, identity_deltas=arrays.identity_deltas * 1.01),
        "geometry": replace(
            arrays,
            model_hash=model_content_hash(
                arrays.name, arrays.shape_names, arrays.neutral + 1, arrays.deltas
            ),
        ),
    }
    hashes = {k: stimulus_hash(a, rig, regions) for k, a in variants.items()}
    hashes["rig companions"] = stimulus_hash(
        arrays, replace(rig, companions={"mouthClose": "jawOpen"}), regions
    )
    hashes["rig genes"] = stimulus_hash(arrays, replace(rig, genes=rig.genes[:-1]), regions)
    hashes["regions"] = stimulus_hash(arrays, rig, {"all": next(iter(ict_regions().values()))})
    assert base not in hashes.values()
    assert len(set(hashes.values())) == len(hashes)
