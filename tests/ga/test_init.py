"""Generation 0: protocol-generated from the rig's building blocks, or fixed from a file."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from emogen.errors import ConfigError
from emogen.ga.init import fixed_init, protocol_init, read_fixed_sets

EMOTIONS = ("happy", "sad", "angry", "fearful")


def active(face: np.ndarray, names: tuple[str, ...]) -> set[str]:
    return {names[i] for i in np.flatnonzero(face)}


@pytest.mark.parametrize("eye_motion", [True, False])
@pytest.mark.parametrize("lo_hi", [(1, 3), (3, 8), (8, 16)])
def test_protocol_population(ict_model, eye_motion, lo_hi) -> None:
    rig = ict_model.rig
    names = rig.gene_names(eye_motion)
    lo, hi = lo_hi
    for seed in range(30):
        genes, labels = protocol_init(
            rig, eye_motion=eye_motion, activation_range=lo_hi, rng=np.random.default_rng(seed)
        )
        assert genes.shape == (10, len(names))
        assert Counter(labels.tolist()) == {
            **{f"init_{e}": 2 for e in EMOTIONS},
            "init_arbitrary": 1,
            "init_neutral": 1,
        }
        assert np.all((genes >= 0) & (genes < 1))
        for face, label in zip(genes, labels, strict=True):
            on = active(face, names)
            if label == "init_neutral":
                assert not on
                continue
            if label == "init_arbitrary":
                assert lo <= len(on) <= min(hi, len(names))
                continue
            e = rig.emotions[label.removeprefix("init_")]
            core = [g for g in e.core if g in names]
            blocks = [g for g in e.blocks if g in names]
            assert on <= set(blocks)
            # n ~ U{lo..hi}, capped at the emotion's blocks
            assert min(lo, len(blocks)) <= len(on) <= min(hi, len(blocks))
            # core genes first, then optional ones
            if len(on) <= len(core):
                assert on <= set(core)
            else:
                assert set(core) <= on


def test_protocol_order_is_shuffled_and_reproducible(ict_model) -> None:
    rig = ict_model.rig
    a = protocol_init(rig, rng=np.random.default_rng(1))
    b = protocol_init(rig, rng=np.random.default_rng(1))
    np.testing.assert_array_equal(a[0], b[0])
    assert a[1].tolist() == b[1].tolist()
    positions = {
        tuple(protocol_init(rig, rng=np.random.default_rng(s))[1].tolist()).index("init_neutral")
        for s in range(40)
    }
    assert len(positions) > 5


def test_protocol_activation_counts_cover_the_range(ict_model) -> None:
    rig = ict_model.rig
    counts = Counter()
    for seed in range(200):
        genes, labels = protocol_init(rig, activation_range=(2, 5), rng=np.random.default_rng(seed))
        counts.update((genes[labels == "init_arbitrary"] > 0).sum(1).tolist())
    assert set(counts) == {2, 3, 4, 5}


def test_eye_blocks_skipped_without_eye_motion(ict_model) -> None:
    rig = ict_model.rig
    names = rig.gene_names(False)
    assert "eyeBlink" in rig.emotions["sad"].blocks and "eyeBlink" not in names
    for seed in range(20):
        genes, labels = protocol_init(
            rig, eye_motion=False, activation_range=(8, 16), rng=np.random.default_rng(seed)
        )
        sad = genes[labels == "init_sad"]
        assert np.all((sad > 0).sum(1) == 7)  # 8 blocks, one of them an eye gene


def test_protocol_unknown_emotion(ict_model) -> None:
    with pytest.raises(ConfigError, match="unknown emotion 'bored'"):
        protocol_init(ict_model.rig, emotions=("bored",), rng=np.random.default_rng(0))


def test_packaged_fixed_sets(ict_model) -> None:
    rig = ict_model.rig
    sets = read_fixed_sets(None, rig)
    assert sets.shape == (3, 10, 30)
    assert np.all((sets >= 0) & (sets <= 1))
    assert np.all(sets[:, :, rig.gene_index("jawOpen")] == 0)
    complexity = (sets > 0).sum(2).mean(1)
    assert complexity[0] < complexity[1] < complexity[2]
    assert read_fixed_sets(None, rig, eye_motion=False).shape == (3, 10, 24)
    genes, labels, option = fixed_init(sets, 2, rng=np.random.default_rng(0))
    np.testing.assert_array_equal(genes, sets[1])
    assert option == 2 and set(labels.tolist()) == {"init_fixed"}
    drawn = {fixed_init(sets, None, rng=np.random.default_rng(s))[2] for s in range(30)}
    assert drawn == {1, 2, 3}
    with pytest.raises(ConfigError, match="fixed_option must be in"):
        fixed_init(sets, 4, rng=np.random.default_rng(0))


def write_sets(tmp_path: Path, faces: str, n: int = 10) -> Path:
    path = tmp_path / "init.toml"
    body = ",\n".join([faces] + ["{}"] * (n - 1))
    path.write_text(f"[[sets]]\nfaces = [\n{body}\n]\n")
    return path


def test_fixed_file_shape_names_must_be_symmetric(ict_model, tmp_path: Path) -> None:
    rig = ict_model.rig
    ok = write_sets(tmp_path, "{mouthSmile_L = 0.3, mouthSmile_R = 0.3, jawOpen = 0.5}")
    genes = read_fixed_sets(ok, rig)[0]
    assert genes[0, rig.gene_index("mouthSmile")] == 0.3
    bad = write_sets(tmp_path, "{mouthSmile_L = 0.3}")
    with pytest.raises(ConfigError, match="set 1 face 1: gene 'mouthSmile' has unequal"):
        read_fixed_sets(bad, rig)


@pytest.mark.parametrize(
    ("face", "n", "match"),
    [
        ("{jawOpen = 0.5}", 9, "set 1 has 9 faces; the population has 10"),
        ("{jawOpn = 0.5}", 10, "set 1 face 1: unknown shape or gene 'jawOpn'"),
        ("{jawOpen = 1.5}", 10, r"weight of 'jawOpen' must be in \[0, 1\]"),
        ("{jawLeft = 0.5}", 10, "shape 'jawLeft' is not evolved"),
    ],
)
def test_fixed_file_errors(ict_model, tmp_path: Path, face, n, match) -> None:
    with pytest.raises(ConfigError, match=match):
        read_fixed_sets(write_sets(tmp_path, face, n), ict_model.rig)


def test_fixed_file_unknown_key(ict_model, tmp_path: Path) -> None:
    path = tmp_path / "init.toml"
    path.write_text("[[sets]]\nfacse = []\n")
    with pytest.raises(ConfigError, match="unknown key 'facse'"):
        read_fixed_sets(path, ict_model.rig)
