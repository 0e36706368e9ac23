"""The first wave of a launch: participants who arrive at once find no completed session whose
faces they could label as others' faces. ``study simulate --arrivals concurrent N`` shows it,
``study check`` and the dashboard say so, and a pool of others' faces from before the study
(``others_pool``: a pilot's export) gives everyone scored others' faces from the first
participant on — recorded, exported and replayed as such."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.cli.app import app
from emogen.errors import ConfigError
from emogen.study.check import check_study
from emogen.study.config import study_from_dict
from emogen.study.dashboard import block_notes, design_notes
from emogen.study.export import export_tables, write_export
from emogen.study.replay import replay_session
from emogen.study.simulate import SimulationPlan, simulate_study
from emogen.study.storage import Store
from emogen.tasks.simulated import SimulatedDesign

STUDY: dict[str, Any] = {
    "name": "wave",
    "seed": 9,
    "emotions": ["happy", "sad", "angry", "fearful"],
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 5},
    "blocks": [
        {"task": "evolve", "name": "make"},
        {"task": "categorise", "name": "label", "own": True, "others": 4, "random": 1},
    ],
}


def run(
    tmp_path: Path, model: Any, name: str, data: dict[str, Any], n: int, wave: int
) -> tuple[dict[str, pd.DataFrame], Store]:
    url = f"sqlite:///{tmp_path / f'{name}.sqlite'}"
    plan = SimulationPlan(
        study_from_dict(data), url, 3, n, SimulatedDesign(), False, concurrent=wave
    )
    simulate_study(plan, model=model)
    store = Store(url)
    return export_tables(store), store


def others_of(tables: dict[str, pd.DataFrame]) -> pd.DataFrame:
    r = tables["categorise_responses"]
    return r[r["source"] == "other"]


def with_pool(pool: Path | None) -> dict[str, Any]:
    blocks = [dict(b) for b in STUDY["blocks"]]
    if pool is not None:
        blocks[1]["others_pool"] = str(pool)
    return {**STUDY, "blocks": blocks}


def test_a_concurrent_wave_without_a_pool_gets_only_fallback_faces(
    tmp_path: Path, ict_model: Any
) -> None:
    tables, store = run(tmp_path, ict_model, "nopool", STUDY, n=4, wave=4)
    try:
        others = others_of(tables)
        assert len(others) == 4 * 4 and others["fallback"].all()
        (note,) = block_notes(store, study_from_dict(STUDY), (1,))
        assert "block 2: 16 of the 16 others' faces drawn so far (100%) were fallback" in note
    finally:
        store.dispose()
    # one after another, the later participants find completed sessions
    tables, store = run(tmp_path, ict_model, "sequential", STUDY, n=4, wave=1)
    store.dispose()
    fell = others_of(tables).groupby("participant_id")["fallback"].mean()
    assert fell["sim-0001"] == 1.0 and fell["sim-0004"] == 0.0
    # the check warns before anyone takes part, with the expected share; so does the dashboard
    (expected,) = design_notes(study_from_dict(STUDY))
    assert expected.startswith("expected (blocks[2].others): until a session is complete")
    (warning,) = check_study(study_from_dict(STUDY)).warnings
    assert warning.where == "blocks[2].others"
    assert "expected fallback share 100% of the 4 others' faces (4 of 9 faces)" in warning.message


def test_a_pool_from_a_pilot_gives_the_first_wave_scored_others_faces(
    tmp_path: Path, ict_model: Any
) -> None:
    pilot, store = run(tmp_path, ict_model, "pilot", STUDY, n=3, wave=1)
    store.dispose()
    write_export(pilot, tmp_path / "pilot", "csv")
    data = with_pool(tmp_path / "pilot")
    assert check_study(study_from_dict(data)).warnings == []
    assert design_notes(study_from_dict(data)) == []
    tables, store = run(tmp_path, ict_model, "launch", data, n=5, wave=5)
    try:
        others = others_of(tables)
        per_person = others.groupby("participant_id")["fallback"].agg(["size", "sum"])
        assert (per_person["size"] == 4).all() and (per_person["sum"] == 0).all()
        # each pooled face is the pilot's final face at its row, for the emotion it was made for
        final = pilot["final_faces"].reset_index(drop=True)
        for _, r in others.iterrows():
            row = final.iloc[int(r["source_row"])]
            assert r["intended"] == row["emotion"] and r["identity"] == row["identity"]
        # balanced over the labels: each participant sees 4 different intended emotions
        assert (others.groupby("participant_id")["intended"].nunique() == 4).all()
        assert block_notes(store, study_from_dict(data), (1,)) == []
        sid = int(tables["sessions"]["session_id"].iloc[0])
        report = replay_session(store, sid, ict_model.rig, ict_model.model_hash, model=ict_model)
        assert report.ok and report.stimuli == 9, report.mismatches
    finally:
        store.dispose()


def test_pool_tables_that_cannot_work_are_refused(tmp_path: Path, ict_model: Any) -> None:
    blocks = [dict(b) for b in STUDY["blocks"]]
    blocks[1] = {**blocks[1], "others": 0, "others_pool": str(tmp_path)}
    with pytest.raises(ConfigError, match="others_pool is set but others is 0"):
        study_from_dict({**STUDY, "blocks": blocks})
    unlabelled = tmp_path / "faces.csv"
    unlabelled.write_text("mouthSmile\n0.5\n")
    for pool, words in [
        (unlabelled, "every row needs the emotion its face was made for"),
        (tmp_path, "is a folder without final_faces.parquet or final_faces.csv"),
    ]:
        with pytest.raises(ConfigError, match=words):
            run(tmp_path, ict_model, f"bad{len(words)}", with_pool(pool), n=1, wave=1)


def test_cli_arrivals_concurrent(tmp_path: Path) -> None:
    study = tmp_path / "s.toml"
    study.write_text('name = "s"\n')
    result = CliRunner().invoke(
        app, ["study", "simulate", str(study), "--arrivals", "together", "3"]
    )
    assert result.exit_code == 2 and "--arrivals must be 'sequential 1' or 'concurrent N'" in (
        result.output
    )
