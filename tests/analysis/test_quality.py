"""Quality and exclusions: the position-bias test calibrated under uniform picks and its
statistic against scipy; the exclusion rule on a real simulated study export — nobody of the
simulated participants excluded, a planted careless participant (every elite on tile 0, 100 ms
responses) excluded for it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from emogen.analysis.exclusions import ExclusionRule, apply_exclusions
from emogen.analysis.people import load_people
from emogen.analysis.quality import participant_quality, position_bias


def _uniform_picks(n: int, events: int, m: int, rng: np.random.Generator) -> pd.DataFrame:
    rows = []
    for p in range(n):
        for t in range(events):
            for pos in rng.choice(10, size=m, replace=False):
                rows.append((f"p{p}", p, t, 0, 0, int(pos)))
    cols = ["participant_id", "session_id", "trial", "attempt", "generation", "position"]
    return pd.DataFrame(rows, columns=cols)


def test_position_bias_is_calibrated_under_uniform_picks() -> None:
    """300 participants picking 3 of 10 tiles at random in 12 generations: p < 0.05 for
    15 ± 2 SE·… (binomial SE 3.8: between 5 and 27); the statistic is scipy's chi-square."""
    rng = np.random.default_rng(3)
    picks = _uniform_picks(300, 12, 3, rng)
    table, overall = position_bias(picks, 10, draws=1000, rng=rng)
    rejected = int((table["p_mc"] < 0.05).sum())
    assert 5 <= rejected <= 27, rejected
    assert overall["p_mc"] > 0.001
    first = picks[picks["participant_id"] == "p0"]
    counts = np.bincount(first["position"], minlength=10)
    assert table.iloc[0]["chi2"] == pytest.approx(stats.chisquare(counts).statistic)


def test_position_bias_finds_a_biased_picker() -> None:
    rng = np.random.default_rng(4)
    picks = _uniform_picks(5, 12, 1, rng)
    picks.loc[picks["participant_id"] == "p2", "position"] = 0
    table, overall = position_bias(picks, 10, draws=1000, rng=rng)
    assert table.set_index("participant_id").loc["p2", "p_mc"] < 0.01
    assert overall["p_mc"] < 0.01


STUDY: dict[str, Any] = {
    "name": "quality",
    "seed": 5,
    "emotions": ["happy", "sad"],
    "identities": ["generic"],
    "repetitions": 4,
    "ga": {"generations": 4, "min_selections": 1, "max_selections": 5},
    "blocks": [{"task": "evolve"}],
}


@pytest.fixture(scope="module")
def export(ict_model, tmp_path_factory: pytest.TempPathFactory) -> Path:  # type: ignore[no-untyped-def]
    from emogen.study.config import study_from_dict
    from emogen.study.export import export_tables, write_export
    from emogen.study.simulate import SimulationPlan, simulate_study
    from emogen.study.storage import Store

    root = tmp_path_factory.mktemp("quality")
    url = f"sqlite:///{root / 'q.sqlite'}"
    from emogen.tasks.simulated import SimulatedDesign

    plan = SimulationPlan(
        study_from_dict(STUDY),
        url,
        seed=1,
        participants=4,
        design=SimulatedDesign(),
        shuffle_prototypes=False,
    )
    simulate_study(plan, model=ict_model)
    store = Store(url)
    try:
        write_export(export_tables(store), root / "export", "parquet")
    finally:
        store.dispose()
    return root / "export"


def _plant_careless(export: Path, out: Path, who: str) -> None:
    """Every elite of ``who`` moved to tile 0 and every response time set to 100 ms."""
    import shutil

    shutil.copytree(export, out)
    s, f = pd.read_parquet(out / "selections.parquet"), pd.read_parquet(out / "faces.parquet")
    key = ["session_id", "trial", "attempt", "generation"]
    tile0 = f[f["position"] == 0][[*key, "face_id"]].rename(columns={"face_id": "tile0"})
    s = s.merge(tile0, on=key, how="left")
    mine = (s["participant_id"] == who) & (s["role"] == "elite")
    s.loc[mine, "face_id"] = s.loc[mine, "tile0"]
    s.loc[s["participant_id"] == who, "client_response_ms"] = 100.0
    s.drop(columns="tile0").to_parquet(out / "selections.parquet")


def test_exclusions_spare_simulated_participants_and_catch_a_careless_one(
    export: Path, tmp_path: Path
) -> None:
    people = load_people(export)
    kept, table = apply_exclusions(people, ExclusionRule())
    assert not table["excluded"].any(), table
    assert kept.n_participants == 4
    assert (table["g0_events"] == 8).all()
    who = sorted(people.faces["participant_id"])[1]
    _plant_careless(export, tmp_path / "careless", who)
    careless = load_people(tmp_path / "careless")
    kept, table = apply_exclusions(careless, ExclusionRule())
    row = table.set_index("participant_id").loc[who]
    assert row["excluded"] and row["fast"] and row["one_tile"] and row["keeps_tile0"]
    assert table["excluded"].sum() == 1
    assert who not in set(kept.faces["participant_id"]) and kept.n_participants == 3
    assert who not in set(kept.selections["participant_id"])
    quality = participant_quality(careless)
    assert quality.set_index("participant_id").loc[who, "median_rt_ms"] == 100
    assert (quality["trials_finished"] == 8).all()


def test_the_quality_section_says_who_is_excluded_and_never_claims_it_without_a_rule(
    export: Path, tmp_path: Path
) -> None:
    """With the rule: the careless participant excluded, and the position-bias test a typed
    result whose p is the one in its record. With ``--no-exclusions``: nobody excluded in the
    JSON or the text; the default rule's verdict given for information only."""
    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.analysis.analyse_people import prepare_people, quality_first

    who = sorted(load_people(export).faces["participant_id"])[1]
    _plant_careless(export, tmp_path / "careless", who)
    for opts, excluded in ((AnalysisOptions(), [who]), (AnalysisOptions(exclusions=None), [])):
        prepared = prepare_people(tmp_path / "careless", opts)
        sections = quality_first(prepared, tmp_path / "report", opts)
        quality = sections[0].data["quality"]
        text = " ".join(str(getattr(b, "text", "")) for s in sections for b in s.blocks)
        assert quality["excluded_ids"] == excluded and quality["excluded"] == len(excluded)
        assert sorted(prepared.excluded) == excluded
        (bias,) = sections[0].results
        assert bias.name == "quality.position_bias" and bias.n == 4
        assert bias.p == quality["position_bias"]["p"] and 0 < bias.p <= 1
        if excluded:
            assert "1 of 4 participants excluded; 3 kept" in text
        else:
            assert quality["default_rule_would_exclude"] == [who]
            assert "No exclusion rule applied" in text and "excluded by the rule" not in text
            assert f"would exclude 1 of 4 ({who})" in text


def test_the_rule_is_applied_once_and_the_report_shows_that_table(
    export: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """One application of the exclusion rule per analysis (in ``prepare_people``): the report's
    exclusion table (``tables/quality_exclusions.csv``) is the rule computed again, plainly, on
    the export; under ``--no-exclusions`` nobody is excluded, the report says so, and the table
    is the default rule's, for information."""
    from emogen.analysis import analyse_people
    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.analysis.results import write_analysis

    who = sorted(load_people(export).faces["participant_id"])[1]
    careless = tmp_path / "careless"
    _plant_careless(export, careless, who)
    calls: list[int] = []

    def counted(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        return apply_exclusions(*args, **kwargs)

    monkeypatch.setattr(analyse_people, "apply_exclusions", counted)
    for opts, excluded in ((AnalysisOptions(), [who]), (AnalysisOptions(exclusions=None), [])):
        calls.clear()
        out = tmp_path / f"report-{len(excluded)}"
        prepared = analyse_people.prepare_people(careless, opts)
        sections = analyse_people.quality_first(prepared, out, opts)
        write_analysis("quality", out, sections, {})
        assert calls == [1]
        shown = pd.read_csv(out / "tables" / "quality_exclusions.csv", keep_default_na=False)
        _, plain = apply_exclusions(load_people(careless), opts.exclusions or ExclusionRule())
        cols = ["participant_id", "excluded", "reasons"]
        assert shown[cols].astype(str).values.tolist() == plain[cols].astype(str).values.tolist()
        assert sorted(prepared.excluded) == excluded
        assert sections[0].data["quality"]["excluded_ids"] == excluded
        assert prepared.kept is not None and prepared.kept.n_participants == 4 - len(excluded)
        md = (out / "README.md").read_text()
        if not excluded:
            assert "No exclusion rule applied" in md and "excluded by the rule above" not in md
            assert plain.set_index("participant_id").loc[who, "excluded"]  # flagged only
