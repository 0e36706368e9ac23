"""Study config: validation with errors that name the key; trial design and order."""

from __future__ import annotations

import hashlib
import json
from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest

from emogen.appearance.identities import PRESETS, Identity
from emogen.appearance.params import Appearance
from emogen.errors import ConfigError
from emogen.study.check import check_identities
from emogen.study.config import (
    StudyConfig,
    demo_study_path,
    load_study_config,
    study_from_dict,
)
from emogen.study.design import balanced_latin_square, trial_order


def test_demo_study_loads() -> None:
    cfg = load_study_config(demo_study_path())
    assert cfg.name == "demo" and cfg.n_trials == 2
    assert cfg.prompt_for("happy") == "Make the face look HAPPY"
    assert len(cfg.config_hash()) == 64


@pytest.mark.parametrize(
    ("data", "match"),
    [
        ({"emotionz": ["happy"]}, "unknown key 'emotionz'"),
        ({"order": "shuffled"}, "'order' must be"),
        ({"repetitions": 0}, "'repetitions' must be >= 1"),
        ({"emotions": []}, "'emotions'"),
        ({"emotions": ["happy", "happy"]}, "must not repeat"),
        ({"ga": {"generations": -1}}, "'ga.generations' must be >= 0"),
        ({"ga": {"mutaton_genes": 1}}, r"unknown key 'mutaton_genes' in \[ga\]"),
        ({"rating": {"points": 1}}, "'rating.points' must be >= 2"),
        (
            {"completion": {"redirect_url": "ftp://x"}},
            "'completion.redirect_url' must start with http",
        ),
        ({"participant_param": "PROLIFIC PID"}, "participant_param"),
        ({"name": "has space"}, "'name'"),
        (
            {"framing": "ovl"},
            r"'framing' must be 'face' or 'oval' \(did you mean 'oval'\?\); got 'ovl'",
        ),
        ({"framing": "Face"}, r"did you mean 'face'\?\); got 'Face'"),
        ({"framing": "head"}, r"'framing' must be 'face' or 'oval': 'head' .* too small"),
        ({"framing": "square"}, r"'framing' must be 'face' or 'oval'; got 'square'"),
    ],
)
def test_errors_name_the_key(data: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        study_from_dict(data, "study.toml")


def test_toml_errors_and_relative_paths(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'x'\norder = 'sideways'\n")
    with pytest.raises(ConfigError, match=r"invalid config .*bad.toml: 'order' must be"):
        load_study_config(bad)
    good = tmp_path / "good.toml"
    good.write_text("name = 'x'\nmodel = 'models/face'\n")
    assert load_study_config(good).model == (tmp_path / "models" / "face").resolve()


def test_identities_must_be_presets_or_the_studys_own(ict_model) -> None:  # type: ignore[no-untyped-def]
    check_identities(study_from_dict({"identities": ["generic", "male", "female"]}), ict_model.rig)
    check_identities(study_from_dict({"identities": list(PRESETS)}), ict_model.rig, ict_model)
    with pytest.raises(
        ConfigError, match=r"'identities' must be among .*female-light.*\['alien'\]"
    ):
        check_identities(study_from_dict({"identities": ["alien"]}), ict_model.rig)
    typo = study_from_dict({"identities": ["my_face"], "identity": {"my_fac": {}}})
    with pytest.raises(ConfigError, match=r"my_fac\).*got \['my_face'\]"):
        check_identities(typo, ict_model.rig)


OWN_IDENTITY = """
name = "own"
identities = ["female-dark", "my_face", "coeffs"]
[identity.my_face]
shape = "male"
skin_tone = 6.5
brow_colour = "#3A2A20"
hair = "none"
beard_shadow = 0.3
[identity.coeffs]
shape = [0.5, -0.25]
"""


def test_study_defines_its_own_identities(tmp_path: Path, ict_model) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "own.toml"
    path.write_text(OWN_IDENTITY)
    cfg = load_study_config(path)
    check_identities(cfg, ict_model.rig, ict_model)
    mine = cfg.identity_of("my_face")
    assert mine == Identity(
        shape="male",
        appearance=Appearance(skin_tone=6.5, brow_colour="#3a2a20", hair="none", beard_shadow=0.3),
    )
    assert cfg.study_identities() == {
        "female-dark": PRESETS["female-dark"],
        "my_face": mine,
        "coeffs": Identity(shape=(0.5, -0.25)),
    }
    assert cfg.n_trials == 3
    # the engine sees the shape preset; coefficient shapes share the generic rig
    assert [cfg.ga_for(n).identity for n in cfg.identities] == ["female", "male", "generic"]
    # the recorded config (canonical JSON) rebuilds the same identities
    again = StudyConfig.model_validate(json.loads(cfg.canonical_json()))
    assert again == cfg and again.config_hash() == cfg.config_hash()
    assert json.loads(cfg.canonical_json())["identity"]["my_face"]["skin_tone"] == 6.5


def test_studies_without_own_identities_keep_their_hash() -> None:
    cfg = study_from_dict({"identities": ["male", "female"]})
    assert "identity" not in json.loads(cfg.canonical_json())
    dumped = cfg.model_dump(mode="json")
    del dumped["identity"]
    del dumped["collect_user_agent"]  # (schema 2) at its default, it leaves the hash alone too
    del dumped["blocks"]  # (schema 5) a study of one evolve block, written without [[blocks]]
    for key in ("custom_emotions", "participant_required", "counterbalance"):  # #32, at defaults
        del dumped[key]
    del dumped["framing"]  # (#29) the face framing, as every study showed before
    del dumped["embed_origins"]  # where it may be embedded is no part of the hash (#33)
    del dumped["block_order"], dumped["reordered_blocks"]  # (#39) at defaults: blocks in order
    del dumped["retest_of"]  # (#39) not a retest
    del dumped["resume"]  # (#40) resuming by the session's link, as every study did before
    text = json.dumps(dumped, sort_keys=True, separators=(",", ":"))
    assert cfg.config_hash() == hashlib.sha256(text.encode()).hexdigest()


@pytest.mark.parametrize(
    ("table", "match"),
    [
        ({"my_face": {"skin_tonee": 3}}, r"my_face.*unknown key 'skin_tonee'"),
        ({"my_face": {"skin_tone": 11}}, r"my_face.*'skin_tone'.*11"),
        ({"my_face": {"brow_colour": "brown"}}, r"my_face.*'brow_colour'.*brown"),
        ({"my_face": {"shape": [1, "x"]}}, r"my_face.*shape must be"),
        ({"male": {"skin_tone": 3}}, "identity 'male' is a preset"),
        ({"has space": {}}, "identity name must be"),
    ],
)
def test_own_identity_errors_name_the_key(table: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        study_from_dict({"identity": table}, "study.toml")


def test_own_identity_shapes_must_fit_the_model(ict_model) -> None:  # type: ignore[no-untyped-def]
    bad_shape = study_from_dict({"identities": ["x"], "identity": {"x": {"shape": "alien"}}})
    with pytest.raises(ConfigError, match="identity 'x' has shape 'alien'"):
        check_identities(bad_shape, ict_model.rig)
    k = ict_model.n_identity_modes
    too_long = study_from_dict({"identities": ["x"], "identity": {"x": {"shape": [0.1] * (k + 1)}}})
    with pytest.raises(ConfigError, match=f"identity 'x'.*{k + 1} coefficients"):
        check_identities(too_long, ict_model.rig, ict_model)


def test_trials_are_emotions_times_identities_times_repetitions() -> None:
    cfg = study_from_dict(
        {"emotions": ["happy", "sad", "angry"], "identities": ["male", "female"], "repetitions": 2}
    )
    conds = cfg.conditions()
    assert cfg.n_trials == len(conds) == 12 and len(set(conds)) == 12


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6, 7])
def test_latin_square_is_balanced(n: int) -> None:
    rows = balanced_latin_square(n)
    assert len(rows) == (n if n % 2 == 0 else 2 * n)
    for row in rows:
        assert sorted(row) == list(range(n))
    for col in range(n):  # every condition equally often in every position
        counts = np.bincount([r[col] for r in rows], minlength=n)
        assert len(set(counts)) == 1
    if n > 1:  # every ordered pair adjacent equally often (first-order carry-over balance)
        pairs = np.zeros((n, n), int)
        for row in rows:
            for a, b in pairwise(row):
                pairs[a, b] += 1
        off = pairs[~np.eye(n, dtype=bool)]
        assert len(set(off)) == 1


def test_orders_random_latin_and_fixed() -> None:
    base = {"emotions": ["a", "b", "c", "d"]}
    rnd = study_from_dict({**base, "order": "random"})
    o1 = trial_order(rnd, slot=0, rng=np.random.default_rng(5))
    o2 = trial_order(rnd, slot=0, rng=np.random.default_rng(5))
    assert o1 == o2 and sorted(o1.order) == [0, 1, 2, 3] and o1.kind == "random"
    latin = study_from_dict({**base, "order": "latin_square"})
    rows = [trial_order(latin, slot=k, rng=np.random.default_rng(0)) for k in range(5)]
    assert [r.row for r in rows] == [0, 1, 2, 3, 0]
    assert rows[0].order == (0, 1, 3, 2) and rows[4].order == rows[0].order
    fixed = study_from_dict({**base, "order": "fixed"})
    assert trial_order(fixed, slot=3, rng=np.random.default_rng(0)).order == (0, 1, 2, 3)


def test_the_default_instructions_say_what_each_task_asks() -> None:
    """A study with a categorise block says how to answer it; one without keeps the GA's text
    (and so its config hash); a study's own instructions are kept as written."""
    from emogen.study.config import DEFAULT_INSTRUCTIONS, study_from_dict

    flat = study_from_dict({"name": "a", "emotions": ["happy", "sad"]})
    assert flat.instructions == DEFAULT_INSTRUCTIONS
    both = study_from_dict(
        {
            "name": "b",
            "emotions": ["happy", "sad"],
            "blocks": [{"task": "evolve"}, {"task": "categorise", "random": 2}],
        }
    )
    assert both.instructions.startswith(DEFAULT_INSTRUCTIONS)
    assert "one face at a time" in both.instructions and "Continue" in both.instructions
    only = study_from_dict(
        {"name": "c", "emotions": ["happy", "sad"], "blocks": [{"task": "categorise", "random": 2}]}
    )
    assert "ten faces" not in only.instructions and "one face at a time" in only.instructions
    own = study_from_dict(
        {
            "name": "d",
            "emotions": ["happy", "sad"],
            "instructions": "Mine.",
            "blocks": [{"task": "categorise", "random": 2}],
        }
    )
    assert own.instructions == "Mine."
    again = study_from_dict(both.model_dump(mode="json"))  # the stored config reads back alike
    assert again.instructions == both.instructions


def test_framing_is_part_of_what_participants_saw() -> None:
    face = study_from_dict({"name": "x"})
    oval = study_from_dict({"name": "x", "framing": "oval"})
    assert face.framing == "face" and oval.framing == "oval"
    assert face.config_hash() == study_from_dict({"name": "x", "framing": "face"}).config_hash()
    assert json.loads(oval.canonical_json())["framing"] == "oval"
    assert oval.config_hash() != face.config_hash()
    again = StudyConfig.model_validate(json.loads(oval.canonical_json()))
    assert again == oval
