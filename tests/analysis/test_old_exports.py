"""Exports written before schema ``emogen.study/6`` (no ``final_faces`` table; ``responses`` and
``ratings`` under their old names) analyse with the same figures as the same study's new
export: the final faces derived once (:func:`~emogen.analysis.study_export.derive_final_faces`)
equal the table, and every reader finds the renamed tables."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from emogen.analysis.data import load_dataset
from emogen.analysis.people import load_people
from emogen.study.export import write_export
from tests.export_helpers import MIXED, as_schema5, simulated_tables


@pytest.fixture(scope="module")
def exports(ict_model: Any, tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("old")
    tables = simulated_tables(root, ict_model, MIXED, participants=5, seed=2)
    for fmt in ("parquet", "csv"):
        write_export(tables, root / fmt, fmt)
        as_schema5(root / fmt, root / f"{fmt}-old")
    return root


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_an_old_export_loads_as_the_new_one(exports: Path, fmt: str) -> None:
    new, old = exports / fmt, exports / f"{fmt}-old"
    assert not (old / f"final_faces.{fmt}").exists() and (old / f"responses.{fmt}").is_file()
    a, b = load_dataset(new), load_dataset(old)
    assert a.groups == b.groups and a.generations == b.generations and a.columns == b.columns
    assert len(a.final) == 20  # 5 participants × 2 emotions × 2 repetitions, all finished
    pd.testing.assert_frame_equal(a.final, b.final)
    pd.testing.assert_frame_equal(a.elites, b.elites)
    pd.testing.assert_frame_equal(a.bias, b.bias)
    for x, y in ((a.ratings, b.ratings), (a.responses, b.responses)):
        assert x is not None and y is not None and len(x) and len(x) == len(y)
        pd.testing.assert_frame_equal(
            x.drop(columns="schema_version"), y.drop(columns="schema_version")
        )
    p, q = load_people(new), load_people(old)
    pd.testing.assert_frame_equal(p.faces, q.faces)
    for x, y in ((p.responses, q.responses), (p.ratings, q.ratings)):
        assert x is not None and y is not None and len(x)
        pd.testing.assert_frame_equal(
            x.drop(columns="schema_version"), y.drop(columns="schema_version")
        )
    assert p.ratings is not None and len(p.ratings) == 20  # one per finished evolve trial


def test_the_final_faces_of_the_dataset_are_the_table(exports: Path) -> None:
    """``Dataset.final`` of a study is the ``final_faces`` table, and the elite of each trial's
    last generation (the GA's result) is that face."""
    ds = load_dataset(exports / "parquet")
    table = pd.read_parquet(exports / "parquet" / "final_faces.parquet")
    final = ds.final.set_index("sample")
    assert len(final) == len(table)
    for row in table.to_dict("records"):
        got = final.loc[f"{row['session_id']}:{row['trial']}"]
        for w in ds.columns:
            assert got[w] == row[f"w_{w}"]
        last = ds.elites[(ds.elites["sample"] == got.name)].sort_values("generation").iloc[-1]
        assert last[list(ds.columns)].tolist() == got[list(ds.columns)].tolist()
