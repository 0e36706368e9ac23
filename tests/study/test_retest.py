"""Retest sessions (``retest_of``): the same participants on another day, matched by id,
refused to anyone else, linked in the export, and analysed for between-session reliability
against known answers (planted person-level stability, and day-to-day drift)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.analysis.people import People, load_people
from emogen.analysis.retest import retest_table, retest_text
from emogen.cli.app import app
from emogen.errors import ConfigError
from emogen.study.config import study_from_dict
from emogen.study.errors import StepConflict
from emogen.study.export import export_tables, write_export
from emogen.study.simulate import SimulationPlan, simulate_study
from emogen.study.storage import Store
from emogen.tasks.simulated import SimulatedDesign
from tests.study.drive import run_to_end, service_caller, study_service

FIRST: dict[str, Any] = {
    "name": "first",
    "seed": 4,
    "emotions": ["happy", "sad"],
    "ga": {"generations": 5, "min_selections": 1, "max_selections": 5},
}
RETEST = {**FIRST, "name": "first-retest", "seed": 5, "retest_of": "first"}


def people(faces: pd.DataFrame, genes: list[str]) -> People:
    empty = pd.DataFrame()
    return People(Path("."), faces, empty, empty, tuple(genes), ())


def planted(rng: np.random.Generator, n: int, drift: float, reps: int) -> tuple[People, People]:
    """Faces x = b_i + d_is + e: person effect var 1, day drift var ``drift``, noise var 0.5."""
    genes = [f"g_{k}" for k in range(4)]
    b = rng.normal(size=(n, 4))
    sessions = []
    for _ in range(2):
        d = rng.normal(scale=np.sqrt(drift), size=(n, 4))
        rows = []
        for i in range(n):
            for _ in range(reps):
                face = b[i] + d[i] + rng.normal(scale=np.sqrt(0.5), size=4)
                rows.append(
                    {
                        "participant_id": f"P{i}",
                        "emotion": "happy",
                        "identity": "f",
                        **dict(zip(genes, face, strict=True)),
                    }
                )
        sessions.append(people(pd.DataFrame(rows), genes))
    return sessions[0], sessions[1]


def test_between_and_within_session_icc_recover_planted_values() -> None:
    first, second = planted(np.random.default_rng(3), n=400, drift=0.5, reps=2)
    (row,) = retest_table(first, second).to_dict("records")
    # between: var b / (var b + var drift + var noise / reps) = 1 / 1.75; within: 1.5 / 2
    assert row["icc_between_sessions"] == pytest.approx(1 / 1.75, abs=0.05)
    assert row["ci_low"] < 1 / 1.75 < row["ci_high"]
    assert row["icc_within_session"] == pytest.approx(0.75, abs=0.05)
    assert row["within_ci_low"] < 0.75 < row["within_ci_high"]
    text = retest_text(retest_table(first, second))
    assert "This report's reliability is the between-session one" in text
    assert "between-session ICC 0.5" in text or "between-session ICC 0.6" in text


def test_no_common_participants_is_an_error() -> None:
    first, second = planted(np.random.default_rng(3), n=5, drift=0.5, reps=1)
    second.faces["participant_id"] = "Q" + second.faces["participant_id"]
    with pytest.raises(Exception, match="no participant made the same emotion"):
        retest_table(first, second)


def test_retest_is_only_for_the_first_sessions_participants(tmp_path: Path, ict_model: Any) -> None:
    store = Store(f"sqlite:///{tmp_path / 'r.sqlite'}")
    try:
        first = study_service(study_from_dict(FIRST), store, ict_model)
        token, _ = first.create_session("P-1")
        run_to_end(first.state(token), service_caller(first, token))
        first.create_session("P-2")  # started, never completed
        retest = study_service(study_from_dict(RETEST), store, ict_model)
        for pid, words in [
            ("P-3", "participant 'P-3' has no session of the study 'first'"),
            ("P-2", "participant 'P-2' has not completed the study 'first'"),
            (None, "has no session of the study 'first'"),
        ]:
            with pytest.raises(StepConflict, match=words):
                retest.create_session(pid)
        retest.create_session("P-1")
        sessions = export_tables(store)["sessions"].set_index("participant_id")
        rows = sessions[sessions["study"] == "first-retest"]
        firsts = sessions[sessions["study"] == "first"]["session_id"]
        assert list(rows.index) == ["P-1"]
        assert rows.loc["P-1", "retest_of_session_id"] == firsts["P-1"]
        assert sessions[sessions["study"] == "first"]["retest_of_session_id"].isna().all()
    finally:
        store.dispose()


def test_a_retest_study_cannot_be_its_own_retest() -> None:
    with pytest.raises(ConfigError, match="names this study itself"):
        study_from_dict({**FIRST, "retest_of": "first"})


def test_simulated_retest_of_20_participants(tmp_path: Path, ict_model: Any, ict_dir: Path) -> None:
    url = f"sqlite:///{tmp_path / 'sim.sqlite'}"
    design = SimulatedDesign(spread=1.0)
    for data in (FIRST, RETEST):  # the same seed: the same simulated people, stable prototypes
        plan = SimulationPlan(study_from_dict(data), url, 8, 20, design, False)
        simulate_study(plan, model=ict_model)
    store = Store(url)
    try:
        for name in ("first", "first-retest"):
            write_export(export_tables(store, study=name), tmp_path / name, "csv")
    finally:
        store.dispose()
    result = CliRunner().invoke(
        app,
        [
            "study",
            "retest-reliability",
            str(tmp_path / "first"),
            str(tmp_path / "first-retest"),
            "--out",
            str(tmp_path / "rel"),
            "--json",
        ],
    )
    assert result.exit_code == 0, result.output
    table = pd.read_csv(tmp_path / "rel" / "retest.csv")
    assert list(table["participants"]) == [20, 20]
    # planted person-level stability: each person's faces resemble their own on the other day
    assert (table["ci_low"] > 0).all(), table
    assert table["icc_within_session"].isna().all()  # one repetition: no within-session figure
    assert "no repetitions within the session" in (tmp_path / "rel" / "retest.md").read_text()
    # the null: retest faces given to other people (ids permuted) resemble them no more than
    # anyone's: the interval covers 0
    second = load_people(tmp_path / "first-retest")
    ids = sorted(second.faces["participant_id"].unique())
    moved = dict(zip(ids, ids[1:] + ids[:1], strict=True))
    second.faces["participant_id"] = second.faces["participant_id"].map(moved)
    null = retest_table(load_people(tmp_path / "first"), second)
    assert ((null["ci_low"] < 0) & (null["ci_high"] > 0)).all(), null
    # emogen analyse FIRST RETEST: the same figures in the report, which says what it reports
    args = ["analyse", str(tmp_path / "first"), str(tmp_path / "first-retest")]
    quick = ["--model", str(ict_dir), "--no-render", "--noise-runs", "20"]
    result = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "a"), *quick])
    assert result.exit_code == 0, result.output
    readme = (tmp_path / "a" / "README.md").read_text()
    assert "## Between-session reliability (retest)" in readme
    assert "This report's reliability is the between-session one" in readme
    assert "20 participants analysed (0 excluded by the same rule)" in readme
    first_row = table.iloc[0]
    assert (
        f"between-session ICC {first_row['icc_between_sessions']:.2f} "
        f"[{first_row['ci_low']:.2f}, {first_row['ci_high']:.2f}]"
    ) in readme
    reported = pd.read_csv(tmp_path / "a" / "tables" / "retest.csv")
    assert len(reported) == 2

    missing = tmp_path / "no-such-export"
    bad = CliRunner().invoke(app, [*args[:2], str(missing), "--out", str(tmp_path / "b"), *quick])
    assert bad.exit_code != 0 and str(missing) in bad.output, bad.output
    assert not (tmp_path / "b").exists()
