"""``emogen analyse``'s results type and its one renderer (emogen.analysis.results): a test's
record read into a typed Result (its fields checked against the record written by hand), the
report written from sections (HTML, Markdown, CSV, JSON), and — on a planted study — the
numbers and the report's text equal to main's before the change (tests/data/analyse_planted.*,
written by tests/data/makers/analyse_planted.py at the commit tests/data/README.md names)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pandas as pd
import pytest
from benchmarks.planted_study import PlantedDesign, write_planted_study

from emogen.analysis.analyse import AnalysisOptions, analyse
from emogen.analysis.plan import mark_roles, plan_section
from emogen.analysis.results import (
    HypothesisTest,
    Interval,
    Section,
    check_registered,
    records_in,
    unregistered,
    write_analysis,
)
from emogen.analysis.study_export import StudyExport
from emogen.analysis.task_sections import TaskTools, task_sections

DATA = Path(__file__).resolve().parents[1] / "data"
#: The planted study and options of tests/data/analyse_planted.* (its maker imports them).
DESIGN = PlantedDesign(participants=10, own_weight=0.6, distinctness_sd=0.3)
SEED = 3
OPTIONS = AnalysisOptions(render=False, noise_runs=20, noise_draws=200)

OWN_ADVANTAGE = {
    "test": "paired t",
    "unit": "participant",
    "n_participants": 12,
    "difference": 0.1,
    "ci_low": 0.02,
    "ci_high": 0.18,
    "confidence": 0.9,
    "t": 2.6,
    "df": 11,
    "p": 0.025,
    "dz": 0.75,
    "dz_low": 0.1,
    "dz_high": 1.4,
}


def test_a_test_added_by_its_analysis_is_typed(tmp_path: Path) -> None:
    sec = _one_section(tmp_path)
    (r,) = sec.results
    assert r.test == HypothesisTest(name="paired t", p=0.025, statistic=2.6, df=11.0)
    assert r.estimate == 0.1
    assert r.interval == Interval(0.02, 0.18, 0.9)
    assert (r.unit, r.n, r.family, r.role, r.fit) == (
        "participant",
        12,
        "categorisation.own_advantage",
        "exploratory",
        "ok",
    )
    assert r.effect_size is not None
    assert (r.effect_size.name, r.effect_size.value) == ("dz", 0.75)
    assert r.effect_size.interval == Interval(0.1, 1.4, 0.9)


@pytest.mark.parametrize("p", [float("nan"), None, float("inf")])
def test_a_test_without_a_p_is_refused_and_names_not_run(p: object) -> None:
    with pytest.raises(ValueError, match=r"'x\[a\]'.*not_run"):
        Section(Path(".")).add_test("x[a]", {}, test="t", p=p, n=3)  # type: ignore[arg-type]


def test_a_test_not_run_keeps_its_reason_and_no_made_up_numbers() -> None:
    sec = Section(Path("."))
    record = {"status": "failed", "reason": "2 participants", "p": None}
    r = sec.not_run("categorisation.fields_accuracy", "2 participants", record, n=2)
    assert r.test is None and r.p is None and r.estimate is None and r.interval is None
    assert (r.fit, r.warnings, r.n, r.record) == ("not run", ("2 participants",), 2, record)
    with pytest.raises(ValueError, match="reason"):
        sec.not_run("x", "")


def test_records_are_named_by_their_place_and_item() -> None:
    data = {
        "spread_test": [{"group": "happy", "p": 0.2}, {"group": "sad", "p": 0.01}],
        "conditions": {"emotion": {"p": 0.001}, "note": "x", "n": 3},
        "categorisation": {"hit_rates": [{"p_t": 0.5}]},
    }
    names = [n for n, _ in records_in(data)]
    assert names == [
        "spread_test[happy]",
        "spread_test[sad]",
        "conditions.emotion",
        "categorisation.hit_rates[0]",
    ]


def test_a_p_value_in_the_data_without_its_test_is_refused_by_name(tmp_path: Path) -> None:
    """One path into the plan: a section whose data holds a p that it did not register (with
    add_test or not_run) stops the analysis, naming the record."""
    sec = Section(tmp_path)
    kept, forgotten = {"p": 0.2}, {"p_perm": 0.01}
    sec.data["spread_test"] = [{"group": "happy", **kept}]
    sec.data["conditions"] = {"emotion": forgotten, "identity": {"p": float("nan")}}
    sec.add_test("spread_test[happy]", sec.data["spread_test"][0], test="t", p=0.2, n=5)
    sec.not_run("conditions.identity", "one identity", sec.data["conditions"]["identity"])
    assert unregistered(sec) == ["conditions.emotion"]
    with pytest.raises(ValueError, match=r"\['conditions.emotion'\].*did not register"):
        check_registered([Section(tmp_path), sec])
    sec.add_test("conditions.emotion", forgotten, test="permutation", p=0.01, n=5)
    assert [r.name for r in check_registered([sec])] == [
        "spread_test[happy]",
        "conditions.identity",
        "conditions.emotion",
    ]


def _one_section(out: Path) -> Section:
    sec = Section(out)
    sec.heading("Own vs others")
    sec.paragraph("The participant is the **unit**.")
    sec.table(pd.DataFrame({"group": ["a", "b"], "mean": [0.5, 0.25]}), "means", "Means")
    sec.csv(pd.DataFrame({"x": [1, 2, 3]}), "hidden")
    record = dict(OWN_ADVANTAGE)
    sec.data["categorisation"] = {"own_advantage": record}
    sec.add_test(
        "categorisation.own_advantage",
        record,
        test="paired t",
        p=0.025,
        statistic=2.6,
        df=11,
        n=12,
        estimate=0.1,
        interval=(0.02, 0.18),
        level=0.9,
        effect=("dz", 0.75, 0.1, 1.4),
    )
    return sec


def test_a_test_keeps_its_record_and_an_effect_without_interval(tmp_path: Path) -> None:
    (built,) = _one_section(tmp_path).results
    assert built.record["t"] == 2.6
    without = Section(tmp_path).add_test(
        "x[a]", {}, test="F", p=0.5, n=3, effect=("r", 0.2, None, None)
    )
    assert without.family == "x" and without.interval is None
    assert without.effect_size is not None and without.effect_size.interval is None


def test_the_renderer_writes_every_format_from_the_sections(tmp_path: Path) -> None:
    sec = _one_section(tmp_path)
    results = mark_roles(sec.results, ("categorisation.own_advantage",))
    plan = plan_section(results, ("categorisation.own_advantage",), tmp_path)
    html, md, js = write_analysis("T", tmp_path, [sec, plan], {"source": "here"})
    data = json.loads(js.read_text())
    assert list(data) == ["source", "categorisation", "plan"]
    assert data["categorisation"]["own_advantage"]["role"] == "primary"
    (row,) = data["plan"]["tests"]
    assert row["test"] == "categorisation.own_advantage" and row["p_holm_primary"] == 0.025
    assert (row["estimate"], row["ci_low"], row["ci_high"], row["effect_size"]) == (
        0.1,
        0.02,
        0.18,
        0.75,
    )
    text = md.read_text()
    assert "## Own vs others" in text and "| a | 0.500 |" in text
    assert "hidden" not in text and "hidden" not in html.read_text()  # CSV only
    assert "<strong>unit</strong>" in html.read_text()
    assert (tmp_path / "tables" / "hidden.csv").read_text().splitlines() == ["x", "1", "2", "3"]
    assert pd.read_csv(tmp_path / "tables" / "means.csv")["mean"].tolist() == [0.5, 0.25]
    assert "means" in (tmp_path / "tables" / "col_types.csv").read_text()


def _numbers_equal(main: object, new: object, path: str = "") -> list[str]:
    """Where ``new`` differs from ``main``: keys, lengths, text, or numbers beyond a relative
    1e-7 (another machine's rounding)."""
    if isinstance(main, dict):
        if not isinstance(new, dict) or list(main) != list(new):
            return [f"{path}: keys {list(main)} != {list(new) if isinstance(new, dict) else new}"]
        return [d for k in main for d in _numbers_equal(main[k], new[k], f"{path}.{k}")]
    if isinstance(main, list):
        if not isinstance(new, list) or len(main) != len(new):
            return [f"{path}: length"]
        return [d for i, (a, b) in enumerate(zip(main, new, strict=True)) for d in
                _numbers_equal(a, b, f"{path}[{i}]")]  # fmt: skip
    if isinstance(main, float) and isinstance(new, int | float):
        same = math.isclose(main, new, rel_tol=1e-7, abs_tol=1e-12)
        return [] if same or (math.isnan(main) and math.isnan(new)) else [f"{path}: {main} {new}"]
    return [] if main == new else [f"{path}: {main!r} != {new!r}"]


def _masked(text: str) -> list[str]:
    """The report's lines with every number masked (a last digit may round differently)."""
    return [re.sub(r"\d[\d.,]*(e[+-]?\d+)?", "#", line) for line in text.splitlines()]


@pytest.mark.slow
def test_a_planted_study_gives_mains_numbers_and_report(tmp_path: Path) -> None:
    export = write_planted_study(DESIGN, tmp_path / "export", seed=SEED)
    result = analyse(export, tmp_path / "report", options=OPTIONS)
    new = json.loads((result.out / "analysis.json").read_text().replace(str(export), "EXPORT"))
    main = json.loads((DATA / "analyse_planted.json").read_text())
    assert _numbers_equal(main, new) == []
    assert result.summary["plan"] == new["plan"]
    md = result.markdown.read_text().replace(str(export), "EXPORT")
    assert _masked(md) == _masked((DATA / "analyse_planted.md").read_text())
    by_name = {r.name: r for r in result.results}
    ran = [n for n in by_name if by_name[n].test is not None]
    assert [t["test"] for t in main["plan"]["tests"]] == sorted(
        ran, key=lambda n: by_name[n].role != "primary"
    )
    not_run = [n for n in by_name if by_name[n].test is None]
    assert [t["test"] for t in main["plan"]["not_run"]] == not_run == ["identity.distance"]
    primary = by_name["categorisation.own_distance.primary"]
    assert primary.role == "primary" and primary.unit.startswith("participant")


class _Task:
    """A task whose analysis hook gives back ``answer`` (its section filled with one test, or
    what a wrong hook might return)."""

    def __init__(self, name: str, answer: str) -> None:
        self.name, self.answer = name, answer

    def analysis_section(self, tools: TaskTools) -> object:
        if self.answer == "nothing":
            return None
        if self.answer == "a dict":
            return {"p": 0.5}
        sec = tools.report
        sec.heading(f"{self.name} blocks")
        sec.data[self.name] = record = {"t": 2.0, "p": 0.1}
        sec.add_test(f"{self.name}.test", record, test="t", p=0.1, statistic=2.0, df=3, n=4)
        return sec


def test_a_tasks_section_and_its_test_reach_the_plan(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    tasks = {n: _Task(n, a) for n, a in (("made", "its section"), ("empty", "nothing"))}
    monkeypatch.setattr("emogen.analysis.task_sections.TASKS", tasks)
    steps: list[str] = []
    sections = task_sections(StudyExport(tmp_path), tmp_path, OPTIONS, None, steps.append)
    assert steps == ["made blocks", "empty blocks"] and len(sections) == 1  # None: no section
    (result,) = mark_roles(sections[0].results, ())
    assert (result.name, result.family, result.p, result.n) == ("made.test", "made.test", 0.1, 4)
    _, md, js = write_analysis("T", tmp_path, [*sections, plan_section([result], (), tmp_path)], {})
    data = json.loads(js.read_text())
    assert data["made"] == {"t": 2.0, "p": 0.1, "role": "exploratory"}
    assert [t["test"] for t in data["plan"]["tests"]] == ["made.test"]
    assert "## made blocks" in md.read_text()


def test_a_hook_that_returns_something_else_is_refused_by_the_tasks_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("emogen.analysis.task_sections.TASKS", {"odd": _Task("odd", "a dict")})
    with pytest.raises(TypeError, match=r"task 'odd': analysis_section returned dict"):
        task_sections(StudyExport(tmp_path), tmp_path, OPTIONS, None, lambda _s: None)
