"""Configuration: the paper's defaults, TOML loading, errors that name the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from emogen.config import (
    PAPER_SELECTIONS,
    GAConfig,
    InitConfig,
    SimulationConfig,
    load_config,
    validate_config,
)
from emogen.errors import ConfigError


def test_paper_defaults() -> None:
    c = GAConfig()
    assert (c.population_size, c.random_faces, c.mutation_genes, c.random_genes) == (10, 4, 2, 6)
    assert (c.generations, c.min_selections, c.max_selections) == (10, 1, 10)
    assert c.eye_motion and c.variant == "emogen" and c.identity == "generic"
    assert c.init == InitConfig()
    assert c.init.kind == "protocol" and c.init.activation_range == (3, 8)
    assert c.init.emotions == ("happy", "sad", "angry", "fearful") and c.arbitrary_faces() == 1
    assert PAPER_SELECTIONS == (2, 4, 4, 4, 4, 4, 5, 5, 5, 5, 5)
    s = SimulationConfig(target={"jawOpen": 1.0})
    assert s.runs == 500 and [s.selections_at(g) for g in (0, 1, 5, 6, 10, 30)] == [
        2,
        4,
        4,
        5,
        5,
        5,
    ]


def test_frozen() -> None:
    with pytest.raises(ValueError, match="frozen"):
        GAConfig().generations = 3  # type: ignore[misc]


def test_load_toml(tmp_path: Path) -> None:
    path = tmp_path / "ga.toml"
    path.write_text(
        "generations = 6\nmutation_genes = 3\n[init]\nkind = 'fixed'\nfixed_option = 2\n"
    )
    c = load_config(GAConfig, path)
    assert c.generations == 6 and c.mutation_genes == 3
    assert c.init.kind == "fixed" and c.init.fixed_option == 2


@pytest.mark.parametrize(
    ("toml", "match"),
    [
        ("mutaton_genes = 2", "unknown key 'mutaton_genes'"),
        ("[init]\nkindd = 'fixed'", r"unknown key 'kindd' in \[init\]"),
        ("mutation_genes = -1", "'mutation_genes' must be >= 0; got -1"),
        ("generations = 'ten'", "'generations' must be a whole number"),
        ("[init]\nkind = 'random'", "'init.kind' must be 'protocol' or 'fixed'"),
        ("[init]\nactivation_range = [8, 3]", r"activation_range must be \[lo, hi\]"),
        ("[init]\nactivation_range = [0, 3]", r"'init.activation_range\[1\]' must be >= 1"),
        ("min_selections = 5\nmax_selections = 3", r"min_selections \(5\) must not exceed"),
        ("max_selections = 11", r"max_selections must be at most population_size \(10\)"),
        ("random_faces = 10", "random_faces must leave room for the elite"),
        ("population_size = 6", "protocol initialisation needs population_size >= 9"),
        ("generations =", "not valid TOML"),
    ],
)
def test_errors_name_the_key(tmp_path: Path, toml: str, match: str) -> None:
    path = tmp_path / "ga.toml"
    path.write_text(toml)
    with pytest.raises(ConfigError, match=match):
        load_config(GAConfig, path)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read config file"):
        load_config(GAConfig, tmp_path / "nope.toml")


@pytest.mark.parametrize(
    ("data", "match"),
    [
        ({}, "'target' is required"),
        ({"target": {}}, "'target' must have at least 1 entry"),
        ({"target": {"jawOpen": 0}}, "at least one non-zero weight"),
        ({"target": {"jawOpen": 2}}, "'target.jawOpen' must be <= 1"),
        ({"target": {"jawOpen": 1}, "runs": 0}, "'runs' must be >= 1"),
        (
            {"target": {"jawOpen": 1}, "ga": {"mutaton_genes": 1}},
            r"unknown key 'mutaton_genes' in \[ga\]",
        ),
        ({"target": {"jawOpen": 1}, "selections": [2, 11]}, r"selections must lie within .*\[11\]"),
        (
            {"target": {"jawOpen": 1}, "ga": {"variant": "classical", "max_selections": 5}},
            "classical variant ranks the whole population",
        ),
    ],
)
def test_simulation_config_errors(data, match) -> None:
    with pytest.raises(ConfigError, match=match):
        validate_config(SimulationConfig, data)


@pytest.mark.parametrize(
    ("data", "words"),
    [
        ({"identities": "female-light"}, "'identities' must be a list in square brackets"),
        ({"identities": []}, "'identities' must have at least 1 entry; got []"),
        ({"repetitions": "two"}, "'repetitions' must be a whole number; got 'two'"),
        ({"completion": {"code": 5}}, "'completion.code' must be text in quotes"),
        ({"ga": {"generations": [1]}}, "'ga.generations' must be a whole number"),
    ],
)
def test_study_config_errors_are_in_plain_words(data: dict, words: str) -> None:
    """Not pydantic's words ("must be a valid tuple", "Tuple should have at least 1 item after
    validation"): what a researcher writing TOML needs to read."""
    from emogen.study.config import study_from_dict

    with pytest.raises(ConfigError) as info:
        study_from_dict(data)
    message = str(info.value)
    assert words in message
    for library in (
        "valid tuple",
        "Tuple should",
        "after validation",
        "Input should",
        "valid integer",
    ):
        assert library not in message
