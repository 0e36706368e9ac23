"""Exports written before schema ``emogen.study/6`` (no ``final_faces`` table; ``responses`` and
``ratings`` under their old names) analyse with the same figures as the same study's new
export: the final faces derived once (:func:`~emogen.analysis.study_export.derive_final_faces`)
equal the table, and every reader finds the renamed tables."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen import columns as tidy
from emogen.analysis.data import load_dataset
from emogen.analysis.people import load_people
from emogen.appearance.params import Appearance
from emogen.cli.app import app
from emogen.study.export import identities_from_table, write_export
from tests.export_helpers import (
    MIXED,
    as_schema5,
    read_export_table,
    simulated_tables,
    write_export_table,
)


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


def _before_lip_depth(new: Path, old: Path) -> Path:
    """A copy of ``new`` as exports were written before the ``lip_depth`` appearance parameter
    existed (rig 2): the ``identities`` table without that column, and its letter gone from the column types."""
    shutil.copytree(new, old)
    fmt = "parquet" if (old / "trials.parquet").is_file() else "csv"
    path = old / f"identities.{fmt}"
    table = read_export_table(path)
    at = list(table.columns).index("lip_depth")
    write_export_table(table.drop(columns="lip_depth"), path)
    types = old / tidy.COL_TYPES
    if types.is_file():  # readr's compact spec: one letter per column, in order
        lines = types.read_text().splitlines()
        k = len("identities,") + at
        lines = [f"{ln[:k]}{ln[k + 1 :]}" if ln.startswith("identities,") else ln for ln in lines]
        types.write_text("".join(line + "\n" for line in lines))
    return old


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_an_export_without_a_later_appearance_parameter_analyses(
    exports: Path, fmt: str, ict_dir: Path, tmp_path: Path
) -> None:
    """An export from before an appearance parameter existed reads its identities with that
    parameter at its default (the look those studies had), and ``emogen analyse`` (faces drawn)
    finishes on it."""
    old = _before_lip_depth(exports / fmt, tmp_path / "old")
    new_ids = identities_from_table(read_export_table(exports / fmt / f"identities.{fmt}"))
    old_ids = identities_from_table(read_export_table(old / f"identities.{fmt}"))
    assert old_ids.keys() == new_ids.keys() and old_ids
    for key, ident in old_ids.items():
        assert ident.appearance.lip_depth == Appearance().lip_depth == 0.0
        assert ident == new_ids[key].model_copy(
            update={"appearance": new_ids[key].appearance.model_copy(update={"lip_depth": 0.0})}
        )
    out = tmp_path / "report"
    args = ["analyse", str(old), "--out", str(out), "--noise-runs", "20", "--model", str(ict_dir)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert (out / "index.html").is_file() and (out / "figures" / "mean_faces.png").is_file()
