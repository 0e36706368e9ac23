"""The rig: gene space, symmetry, exclusions, building blocks, TOML validation."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from emogen.errors import ConfigError, ShapeError
from emogen.model.rig_build import load_rig


def test_gene_space_of_ict(ict_model) -> None:
    rig = ict_model.rig
    genes = rig.gene_names()
    assert len(genes) == 30
    assert len(rig.gene_names(eye_motion=False)) == 24
    for lateral in ("jawLeft", "jawRight", "mouthLeft", "mouthRight", "mouthClose"):
        assert lateral in rig.excluded and lateral not in genes
        assert all(lateral not in g.shapes for g in rig.genes)
    assert "mouthSmile" in genes and "mouthSmile_L" not in genes
    # every non-excluded shape belongs to exactly one gene
    covered = [s for g in rig.genes for s in g.shapes]
    assert sorted(covered) == sorted(set(ict_model.shape_names) - set(rig.excluded))
    assert ("mouthSmile_L", "mouthSmile_R") in rig.pairs
    no_eyes = rig.disabled_shapes(eye_motion=False)
    assert {"eyeBlink_L", "eyeLookIn_R", "PupilDilate_L"} <= set(no_eyes)


def test_horizontal_gaze_is_conjugate(ict_model) -> None:
    genes = {g.name: g for g in ict_model.rig.genes}
    assert set(genes["eyeLookLeft"].shapes) == {"eyeLookOut_L", "eyeLookIn_R"}
    assert set(genes["eyeLookRight"].shapes) == {"eyeLookOut_R", "eyeLookIn_L"}


@settings(max_examples=50, deadline=None)
@given(data=st.data(), eye_motion=st.booleans())
def test_expand_is_symmetric_and_contract_inverts_it(ict_model, data, eye_motion) -> None:
    rig = ict_model.rig
    n_genes = len(rig.gene_names(eye_motion))
    genes = data.draw(arrays(np.float64, (3, n_genes), elements=st.floats(0, 1)))
    full = rig.expand(genes, eye_motion)
    index = {s: i for i, s in enumerate(ict_model.shape_names)}
    paired_genes = {frozenset(g.shapes) for g in rig.genes}
    for left, right in rig.pairs:
        if frozenset((left, right)) not in paired_genes:
            continue  # excluded, or regrouped (conjugate gaze)
        np.testing.assert_array_equal(full[:, index[left]], full[:, index[right]])
    for shape in rig.disabled_shapes(eye_motion):
        assert np.all(full[:, index[shape]] == 0)
    # plain-loop reference for one gene at a time
    for g_i, gene in enumerate(rig.active_genes(eye_motion)):
        for s in gene.shapes:
            np.testing.assert_array_equal(full[:, index[s]], genes[:, g_i])
    np.testing.assert_allclose(rig.contract(full, eye_motion), genes, atol=1e-12)


def test_emotion_blocks_name_real_genes(ict_model) -> None:
    rig = ict_model.rig
    assert {"happy", "sad", "angry", "fearful", "surprised", "disgusted"} <= set(rig.emotions)
    genes = set(rig.gene_names())
    for e in rig.emotions.values():
        assert set(e.blocks) <= genes and e.core and e.source
    assert set(rig.emotions["happy"].core) == {"cheekSquint", "mouthSmile", "mouthLowerDown"}


def test_weights_from_names(ict_model) -> None:
    rig = ict_model.rig
    w = rig.weights_from_names({"mouthSmile": 0.5, "jawOpen": 1.0})
    assert (
        w[ict_model.shape_index("mouthSmile_L")] == 0.5 == w[ict_model.shape_index("mouthSmile_R")]
    )
    with pytest.raises(ShapeError, match="unknown shape or gene 'mouthSmil'"):
        rig.weights_from_names({"mouthSmil": 0.5})
    with pytest.raises(ConfigError, match=r"'jawOpen' must be in \[0, 1\]; got 1.5"):
        rig.weights_from_names({"jawOpen": 1.5})
    with pytest.raises(ShapeError, match=r"\(n_faces, 30\)"):
        rig.expand(np.zeros((1, 29)))


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "rig.toml"
    p.write_text(text)
    return p


def test_rig_toml_errors_name_the_key(ict_model, tmp_path: Path) -> None:
    names = ict_model.shape_names
    with pytest.raises(ConfigError, match="unknown key 'exclude'"):
        load_rig(names, _write(tmp_path, 'name = "x"\n[exclude]\njawLeft = "a"\n'))
    with pytest.raises(ConfigError, match=r"excluded names unknown shape\(s\) \['jawLefft'\]"):
        load_rig(names, _write(tmp_path, 'name = "x"\n[excluded]\njawLefft = "a"\n'))
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_rig(names, _write(tmp_path, 'name = "x\n'))
    with pytest.raises(ConfigError, match=r"gaze.yaw_deg"):
        bad = (
            'name = "x"\n[gaze]\nleft_eyeball="eyeball_left"\nright_eyeball="eyeball_right"\n'
            "look_left=[]\nlook_right=[]\nlook_up=[]\nlook_down=[]\nyaw_deg=400\n"
            "pitch_up_deg=1\npitch_down_deg=1\n"
        )
        load_rig(names, _write(tmp_path, bad))
    with pytest.raises(ConfigError, match="emotion 'happy' names unknown gene"):
        load_rig(
            names,
            _write(
                tmp_path,
                'name = "x"\n[emotions.happy]\naction_units="6+12"\ncore=["smile"]\nsource="s"\n',
            ),
        )
