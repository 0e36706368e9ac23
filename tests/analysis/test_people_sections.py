"""The report sections of items 5–6 on a simulated study: tables written, summary numbers, and
one plain line (no error) where the design cannot support an analysis."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from emogen.analysis.analyse_options import AnalysisOptions
from emogen.analysis.conditions import conditions_section
from emogen.analysis.exclusions import ExclusionRule, apply_exclusions
from emogen.analysis.genes_report import genes_section
from emogen.analysis.quality_report import quality_section
from emogen.analysis.report import Report
from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people


def _text(report: Report) -> str:
    return " ".join(str(getattr(b, "text", "")) for b in report.blocks)


def test_sections_on_a_simulated_study(ict_model, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    design = PeopleDesign(participants=12, repetitions=1, categorise=False, groups=("a", "b"))
    people = as_people(simulate_people(design, ict_model.rig, seed=1))
    report, summary = Report("t", tmp_path), {}
    opts = AnalysisOptions()
    applied = apply_exclusions(people, opts.exclusions or ExclusionRule())
    quality = quality_section(people, tmp_path, opts, rule=opts.exclusions, applied=applied)
    report.blocks += quality.blocks
    summary |= quality.data
    assert quality.results == []  # as_people has no tile positions: no position-bias test
    for section in (genes_section, conditions_section):
        part = section(people, tmp_path, opts, None)
        report.blocks += part.blocks
        summary |= part.data
    report.write()
    for name in (
        "genes_facs",
        "genes_emotion_tests",
        "genes_group_tests",
        "conditions_tests",
        "quality_sessions",
        "quality_exclusions",
    ):
        assert (tmp_path / "tables" / f"{name}.csv").is_file(), name
    assert (tmp_path / "figures" / "genes_emotions.png").is_file()
    assert summary["quality"]["excluded"] == 0
    assert summary["genes"]["emotion_maxt"] > 0
    assert "no selections table" in _text(report)  # as_people has none: no position test
    one = replace(people, faces=people.faces[people.faces["emotion"] == "happy"])
    one = replace(one, faces=one.faces[one.faces["identity"] == "female-medium"])
    parts = [s(one, tmp_path / "one", opts, None) for s in (genes_section, conditions_section)]
    report2 = Report("t", tmp_path / "one")
    report2.blocks = [b for p in parts for b in p.blocks]
    text = _text(report2)
    assert "has one emotion" in text and "one emotion and one identity" in text
