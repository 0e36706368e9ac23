"""``emogen analyse`` loads a study export once (emogen.analysis.study_export.StudyExport): each
table read from disk at most once per analysis, and an old export's final faces (written before
the ``final_faces`` table) derived once — equal to the table a newer export writes."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pandas as pd
import pytest
from benchmarks.planted_study import PlantedDesign, write_planted_study

from emogen.analysis import study_export
from emogen.analysis.analyse import AnalysisOptions, analyse
from emogen.analysis.analyse_people import prepare_people
from emogen.analysis.data import load_dataset
from emogen.analysis.study_export import StudyExport

DESIGN = PlantedDesign(participants=6, emotions=("happy", "sad"), identities=("id1",), n_other=6)


@pytest.fixture
def export(tmp_path: Path) -> Path:
    return write_planted_study(DESIGN, tmp_path / "export", seed=5)


@pytest.fixture
def reads(monkeypatch: pytest.MonkeyPatch) -> Counter[str]:
    """Every Parquet file read (the planted export's tables are Parquet), by name, whoever
    reads it."""
    counted: Counter[str] = Counter()
    read = pd.read_parquet

    def counting(path: Path, *args: object, **kwargs: object) -> pd.DataFrame:
        counted[Path(path).stem] += 1
        return read(path, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(pd, "read_parquet", counting)
    return counted


@pytest.fixture
def derived(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """One entry per derivation of final faces."""
    calls: list[int] = []
    derive = study_export.derive_final_faces

    def counting(*args: object, **kwargs: object) -> pd.DataFrame:
        calls.append(1)
        return derive(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(study_export, "derive_final_faces", counting)
    return calls


@pytest.mark.slow  # a whole analysis
def test_analyse_reads_each_table_once(
    export: Path, tmp_path: Path, reads: Counter[str], derived: list[int]
) -> None:
    opts = AnalysisOptions(render=False, noise_runs=10, noise_draws=100)
    analyse(export, tmp_path / "report", options=opts)
    assert reads["trials"] == 1 and reads["faces"] == 1 and reads["final_faces"] == 1
    assert max(reads.values()) == 1, reads
    assert derived == []  # the export has a final_faces table: nothing derived


@pytest.mark.slow  # a planted study written and loaded twice
def test_an_old_exports_final_faces_are_derived_once_and_equal_the_table(
    export: Path, reads: Counter[str], derived: list[int]
) -> None:
    table = pd.read_parquet(export / "final_faces.parquet")
    (export / "final_faces.parquet").unlink()  # as an export written before the table
    loaded = StudyExport(export)
    ds = load_dataset(loaded, exclude=frozenset({"P001"}))
    prepared = prepare_people(loaded, AnalysisOptions())
    load_dataset(loaded)
    assert len(derived) == 1 and max(reads.values()) == 1, (derived, reads)
    key = ["session_id", "trial"]
    genes = [c for c in table.columns if c.startswith(("g_", "w_"))]
    got = loaded.final_faces().sort_values(key).reset_index(drop=True)
    want = table.sort_values(key).reset_index(drop=True)
    pd.testing.assert_frame_equal(got[key + genes], want[key + genes], check_dtype=False)
    assert prepared.kept is not None and len(prepared.kept.faces) == len(table)
    assert ds.finals is not None and "P001" not in set(ds.finals["participant"])
