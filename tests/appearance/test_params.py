"""Appearance parameters and identities: clear errors that name the bad key and value."""

from __future__ import annotations

import pytest

from emogen.appearance import Appearance, appearance_from_dict
from emogen.appearance.identities import PRESETS, identity_from_dict, resolve_identity
from emogen.errors import ConfigError


def test_unknown_key_and_bad_values_are_named() -> None:
    with pytest.raises(ConfigError, match="unknown key 'skin_tome'"):
        appearance_from_dict({"skin_tome": 3})
    with pytest.raises(ConfigError, match="skin_tone"):
        appearance_from_dict({"skin_tone": 11})
    with pytest.raises(ConfigError, match="brow_colour"):
        appearance_from_dict({"brow_colour": "brown"})
    with pytest.raises(ConfigError, match="hair"):
        appearance_from_dict({"hair": "longg"})


def test_record_rebuilds_the_same_appearance_and_key() -> None:
    a = Appearance(skin_tone=6.5, brow_colour="#AA3322", beard_shadow=0.4, seed=7)
    b = Appearance(**a.record())
    assert a == b and a.key() == b.key()
    assert (
        a.key() != Appearance(skin_tone=6.4, brow_colour="#aa3322", beard_shadow=0.4, seed=7).key()
    )


def test_six_presets_two_sexes_three_tones() -> None:
    six = [n for n in PRESETS if "-" in n and not n.endswith(("-v2", "-v3", "-long"))]
    assert sorted(six) == sorted(
        f"{s}-{t}" for s in ("female", "male") for t in ("light", "medium", "dark")
    )
    tones = {PRESETS[f"female-{t}"].appearance.skin_tone for t in ("light", "medium", "dark")}
    assert len(tones) == 3
    assert all(
        PRESETS[f"male-{t}"].appearance.beard_shadow > 0 for t in ("light", "medium", "dark")
    )


def test_dark_presets_keep_their_look_and_v2_darkens_only_the_lips_and_brows() -> None:
    """Studies recorded with ``female-dark``/``male-dark`` replay by name: their parameters are
    the ones they were recorded with (written out here). The ``-v2`` presets are the same
    faces with deeper lips (and the female's denser brows), nothing else."""
    assert PRESETS["female-dark"].appearance.record() == {
        **Appearance().record(), "skin_tone": 8.0, "brow_thickness": 0.8, "brow_density": 0.9,
        "hairline": 1.0, "lip_colour": 1.15, "redness": 1.1, "brow_colour": "#1e1713",
        "hair_colour": "#1a1411",
    }  # fmt: skip
    assert PRESETS["male-dark"].appearance.record() == {
        **Appearance().record(), "skin_tone": 8.0, "brow_thickness": 1.15, "brow_density": 1.1,
        "hairline": 1.12, "beard_shadow": 0.8, "lip_colour": 0.85, "brow_colour": "#1c1612",
        "hair_colour": "#18120f",
    }  # fmt: skip
    assert Appearance().lip_depth == 0.0
    for sex, changed in (
        ("female", {"lip_depth": 0.15, "brow_density": 1.0}),
        ("male", {"lip_depth": 0.2, "lip_colour": 1.0}),
    ):
        old, new = PRESETS[f"{sex}-dark"], PRESETS[f"{sex}-dark-v2"]
        assert new.shape == old.shape
        diff = {k: v for k, v in new.appearance.record().items() if old.appearance.record()[k] != v}
        assert diff == changed
    with pytest.raises(ConfigError, match=r"'lip_depth'.*0.9"):
        appearance_from_dict({"lip_depth": 0.9})


def test_v3_dark_presets_are_v2_with_deeper_wrinkles_only() -> None:
    """``-v3`` changes the wrinkle strength of the ``-v2`` faces and nothing else; every other
    preset keeps the strength of earlier versions (1)."""
    for sex, strength in (("female", 2.0), ("male", 1.6)):
        old, new = PRESETS[f"{sex}-dark-v2"], PRESETS[f"{sex}-dark-v3"]
        assert new.shape == old.shape
        diff = {k: v for k, v in new.appearance.record().items() if old.appearance.record()[k] != v}
        assert diff == {"wrinkle_strength": strength}
    assert all(p.appearance.wrinkle_strength == 1.0 for n, p in PRESETS.items() if "-v3" not in n)
    for bad in (3.5, -0.1):
        with pytest.raises(ConfigError, match=rf"'wrinkle_strength'.*{bad}"):
            appearance_from_dict({"wrinkle_strength": bad})


def test_lab_identity_from_a_table() -> None:
    ident = identity_from_dict("lab", {"shape": "female", "skin_tone": 7, "hair": "none"})
    assert ident.shape == "female" and ident.appearance.skin_tone == 7
    assert resolve_identity("lab", {"lab": ident}) is ident
    with pytest.raises(ConfigError, match=r"unknown identity 'labb'.*female-dark"):
        resolve_identity("labb", {"lab": ident})
    with pytest.raises(ConfigError, match=r"identity 'x'.*unknown key 'skin'"):
        identity_from_dict("x", {"skin": 3})
