"""Targets and training sets from face tables; the simulation config's new keys."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from emogen.config import MetricConfig, SimulationConfig, validate_config
from emogen.errors import ConfigError, DataError
from emogen.simulate.targets import read_faces, resolve_target, weights_from_table


def test_weights_from_shape_and_gene_columns(ict_model) -> None:
    rig = ict_model.rig
    table = pd.DataFrame({"run": [0, 1], "jawOpen": [0.5, 0.0], "mouthSmile": [0.2, 0.9]})
    w = weights_from_table(table, rig)
    expect = np.stack(
        [
            rig.weights_from_names({"jawOpen": 0.5, "mouthSmile": 0.2}),
            rig.weights_from_names({"mouthSmile": 0.9}),
        ]
    )
    np.testing.assert_array_equal(w, expect)
    with pytest.raises(ConfigError, match="no column is a shape or gene name"):
        weights_from_table(pd.DataFrame({"x": [1.0]}), rig)
    with pytest.raises(ConfigError, match="column 'jawOpen' row 2: empty or missing"):
        weights_from_table(pd.DataFrame({"jawOpen": [0.1, None]}), rig)


def test_target_from_a_file_row(ict_model, tmp_path: Path) -> None:
    rig = ict_model.rig
    path = tmp_path / "faces.csv"
    pd.DataFrame(
        {"jawOpen": [0.2, 0.8], "noseSneer_L": [0.0, 0.3], "noseSneer_R": [0, 0.3]}
    ).to_csv(path, index=False)
    cfg = SimulationConfig(target_file=path, target_row=1)
    target = resolve_target(cfg, rig)
    np.testing.assert_array_equal(
        target.weights, rig.weights_from_names({"jawOpen": 0.8, "noseSneer": 0.3})
    )
    assert target.source["row"] == 1 and len(target.source["sha256"]) == 64
    with pytest.raises(ConfigError, match="has 2 rows: say which with target_row"):
        resolve_target(SimulationConfig(target_file=path), rig)
    with pytest.raises(ConfigError, match=r"target_row must be in \[0, 1\]"):
        resolve_target(SimulationConfig(target_file=path, target_row=5), rig)
    parquet = tmp_path / "one.parquet"
    pd.DataFrame({"mouthSmile": [0.7]}).to_parquet(parquet)
    assert resolve_target(SimulationConfig(target_file=parquet), rig).weights.max() == 0.7
    with pytest.raises(ConfigError, match=r"expected a \.parquet or \.csv"):
        resolve_target(SimulationConfig(target_file=tmp_path / "x.json"), rig)
    with pytest.raises(ConfigError, match="does not exist"):
        resolve_target(SimulationConfig(target_file=tmp_path / "none.csv"), rig)
    over = tmp_path / "over.csv"
    pd.DataFrame({"jawOpen": [1.5]}).to_csv(over, index=False)
    with pytest.raises(ConfigError, match=r"must be in \[0, 1\]"):
        resolve_target(SimulationConfig(target_file=over), rig)


def test_training_rows_by_query(ict_model, tmp_path: Path) -> None:
    path = tmp_path / "train.parquet"
    pd.DataFrame({"rank": [0, -1, 0], "jawOpen": [0.1, 0.2, 0.3]}).to_parquet(path)
    w = read_faces(path, ict_model.rig, query="rank == 0")
    assert w[:, ict_model.rig.shape_names.index("jawOpen")].tolist() == [0.1, 0.3]
    with pytest.raises(ConfigError, match="no rows matching"):
        read_faces(path, ict_model.rig, query="rank == 7")
    with pytest.raises(ConfigError, match="query 'rank ==' on"):
        read_faces(path, ict_model.rig, query="rank ==")


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({}, "'target' is required"),
        ({"target": {"jawOpen": 1}, "target_file": "x.csv"}, "either target or target_file"),
        ({"target": {"jawOpen": 1}, "target_row": 2}, "target_row needs target_file"),
        ({"target": {"jawOpen": 1}, "metric": "cosine"}, "'metric.name' must be"),
        ({"target": {"jawOpen": 1}, "metric": "std_ed"}, "metric 'std_ed' is empirical"),
        ({"target": {"jawOpen": 1}, "noise_temperature": -1}, "'noise_temperature' must be >= 0"),
        ({"target": {"jawOpen": 1}, "metric": {"name": "cd", "variance": 0}}, "'metric.variance'"),
    ],
)
def test_config_errors(data, message) -> None:
    with pytest.raises(ConfigError, match=message):
        validate_config(SimulationConfig, data)


def test_metric_shorthand() -> None:
    cfg = validate_config(SimulationConfig, {"target": {"jawOpen": 1}, "metric": "ed"})
    assert cfg.metric == MetricConfig(name="ed")


def test_a_misspelt_target_column_is_an_error_not_a_different_target(ict_model, tmp_path):  # type: ignore[no-untyped-def]
    path = tmp_path / "target.csv"
    path.write_text("jawOpn,mouthSmile_L,mouthSmile_R\n0.9,0.3,0.3\n")
    with pytest.raises(DataError, match=r"target_file .*target\.csv: unknown column 'jawOpn': "):
        resolve_target(SimulationConfig(target_file=path), ict_model.rig)
    empty = tmp_path / "empty.csv"
    empty.write_text("jawOpen,mouthSmile\n")
    with pytest.raises(DataError, match=r"target_file .*empty\.csv has no rows"):
        resolve_target(SimulationConfig(target_file=empty), ict_model.rig)
    blank = tmp_path / "blank.csv"
    blank.write_text("jawOpen,mouthSmile\n0.5,\n")
    with pytest.raises(DataError, match=r"column 'mouthSmile' row 1: empty or missing weight"):
        resolve_target(SimulationConfig(target_file=blank), ict_model.rig)
