"""The report section on categorise answers: tables, figures and a stated unit for every test;
one line why when the design cannot support the analysis; the older call still works."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.categorisation import categorisation_section
from emogen.analysis.report import Content
from emogen.analysis.results import write_analysis
from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people
from tests.r_readers import dictionary_section, undocumented

DESIGN = PeopleDesign(participants=12, repetitions=1, identities=("female-medium",))


def paragraphs(report: Content) -> list[str]:
    return [b.text for b in report.blocks if type(b).__name__ == "_Paragraph"]  # type: ignore[union-attr]


@pytest.fixture(scope="module")
def people(ict_model: Any):  # type: ignore[no-untyped-def]
    return as_people(simulate_people(DESIGN, ict_model.rig, seed=8))


def test_the_section_of_a_study_with_a_categorise_block(people, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    report = categorisation_section(people, tmp_path, AnalysisOptions(seed=3), None)
    summary = report.data
    tables = set(report.tables)  # written with the report
    assert {
        "categorisation_confusion",
        "categorisation_hit_rates",
        "categorisation_hit_rate_tests",
        "categorisation_accuracy",
        "categorisation_source_tests",
        "categorisation_model_long",
        "categorisation_model_slopes",
        "categorisation_participants",
    } <= tables
    for fig in ("categorisation_confusion", "categorisation_own_distance"):
        assert (tmp_path / "figures" / f"{fig}.png").is_file()
        assert (tmp_path / "figures" / f"{fig}.svg").is_file()
    text = paragraphs(report)
    tests = [t for t in text if " p = " in t or "Test:" in t or "test" in t.lower()]
    assert len(tests) >= 5 and all("participant" in t for t in tests)
    assert any("seed 3" in t for t in text)
    got = summary["categorisation"]
    assert got["n_answers"] == len(people.responses) and got["own_distance"]["primary"]["p"] < 0.05
    # the CSV holds every row of a long table the report shows the head of
    write_analysis("t", report.out, [report], {})
    long = pd.read_csv(tmp_path / "tables" / "categorisation_hit_rates.csv")
    assert len(long) == 12 * 4
    # every column of every table is in docs/data.md
    for path in (tmp_path / "tables").glob("categorisation_*.csv"):
        columns = list(pd.read_csv(path, nrows=1).columns)
        assert not undocumented(columns, "Analysis tables: categorisation"), path.name
        assert f"`{path.stem}`" in dictionary_section("Analysis tables: categorisation")


def test_no_categorise_block_is_one_line(ict_model: Any, tmp_path: Path) -> None:
    design = PeopleDesign(
        participants=4, repetitions=1, identities=("female-medium",), categorise=False
    )
    people = as_people(simulate_people(design, ict_model.rig, seed=1))
    report = categorisation_section(people, tmp_path, AnalysisOptions(), None)
    summary = report.data
    assert paragraphs(report) == [
        "No categorisation analysis: no categorise answers (the study has no categorise block, or nobody has reached it yet)."
    ]
    assert summary["categorisation"]["n_answers"] == 0


def test_the_older_call_with_a_responses_table(people, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    report = categorisation_section(None, tmp_path)
    assert report.blocks == [] and report.data == {} and report.results == []
    report = categorisation_section(people.responses, tmp_path)
    assert report.data["categorisation"]["own_advantage"]["n_participants"] == 12
    assert any("not fitted here" in t for t in paragraphs(report))
