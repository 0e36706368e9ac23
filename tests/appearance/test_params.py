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
        appearance_from_dict({"hair": "long"})


def test_record_rebuilds_the_same_appearance_and_key() -> None:
    a = Appearance(skin_tone=6.5, brow_colour="#AA3322", beard_shadow=0.4, seed=7)
    b = Appearance(**a.record())
    assert a == b and a.key() == b.key()
    assert (
        a.key() != Appearance(skin_tone=6.4, brow_colour="#aa3322", beard_shadow=0.4, seed=7).key()
    )


def test_six_presets_two_sexes_three_tones() -> None:
    six = [n for n in PRESETS if "-" in n]
    assert sorted(six) == sorted(
        f"{s}-{t}" for s in ("female", "male") for t in ("light", "medium", "dark")
    )
    tones = {PRESETS[f"female-{t}"].appearance.skin_tone for t in ("light", "medium", "dark")}
    assert len(tones) == 3
    assert all(
        PRESETS[f"male-{t}"].appearance.beard_shadow > 0 for t in ("light", "medium", "dark")
    )


def test_lab_identity_from_a_table() -> None:
    ident = identity_from_dict("lab", {"shape": "female", "skin_tone": 7, "hair": "none"})
    assert ident.shape == "female" and ident.appearance.skin_tone == 7
    assert resolve_identity("lab", {"lab": ident}) is ident
    with pytest.raises(ConfigError, match=r"unknown identity 'labb'.*female-dark"):
        resolve_identity("labb", {"lab": ident})
    with pytest.raises(ConfigError, match=r"identity 'x'.*unknown key 'skin'"):
        identity_from_dict("x", {"skin": 3})
