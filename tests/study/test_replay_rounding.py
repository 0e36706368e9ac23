"""Replay across machines: a recording whose stored weights differ from this machine's by a few
units in the last place (another CPU's BLAS rounding) replays as matching and reports how far
apart they were; a weight moved by 1e-6 — far above rounding — is still a mismatch. For evolve
faces (from the database and from an export, and through the CLI) and for categorised faces.

The expected deviation is computed here with Python's ``math.nextafter`` on the stored values,
independently of the replay code.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
import typer
from sqlalchemy import select
from typer.testing import CliRunner

from emogen.cli.study import replay_command
from emogen.study.export import export_tables, write_export
from emogen.study.replay import replay_session
from emogen.study.replay_export import replay_exported
from emogen.study.storage import Store
from emogen.study.tables import SessionRow, TrialRow
from emogen.tasks.categorise.tables import StimulusRow
from emogen.tasks.evolve.tables import FaceRow, PopulationRow
from emogen.tasks.rounding import WEIGHT_TOLERANCE, weight_deviation
from tests.study.drive import run_to_end, service_caller
from tests.study.test_categorise import mixed  # noqa: F401  (the fixture)

RECORDED = Path(__file__).parents[1] / "data" / "study_stream1.sqlite"
ULPS = 4


def ulps_up(w: float, k: int = ULPS) -> float:
    for _ in range(k):
        w = math.nextafter(w, math.inf)
    return w


def scaled(old: float, new: float) -> float:
    return abs(new - old) / max(1.0, abs(old))


def _session_faces(db: Any, session_id: int) -> list[FaceRow]:
    return list(
        db.scalars(
            select(FaceRow)
            .join(PopulationRow, FaceRow.population_id == PopulationRow.id)
            .join(TrialRow, PopulationRow.trial_id == TrialRow.id)
            .where(TrialRow.session_id == session_id)
            .order_by(FaceRow.id)
        )
    )


def _nudge_all(store: Store, session_id: int) -> float:
    """Every stored weight of the session a few ULPs up; the largest scaled change."""
    worst = 0.0
    with store.write() as db:
        for face in _session_faces(db, session_id):
            old = json.loads(face.weights)
            new = [ulps_up(w) for w in old]
            worst = max([worst, *(scaled(a, b) for a, b in zip(old, new, strict=True))])
            face.weights = json.dumps(new)
    return worst


@pytest.fixture
def recorded(tmp_path: Path) -> Any:
    copy = tmp_path / "recorded.sqlite"
    shutil.copyfile(RECORDED, copy)
    store = Store(f"sqlite:///{copy}")
    with store.read() as db:
        ids = {s.participant_id: s.id for s in db.scalars(select(SessionRow))}
    yield store, ids["OLD-1"]
    store.dispose()


def test_a_recording_off_by_a_few_ulps_replays_and_1e6_does_not(recorded: Any, ict_model) -> None:
    store, sid = recorded
    rig, mhash = ict_model.rig, ict_model.model_hash
    exact = replay_session(store, sid, rig, mhash, model=ict_model)
    assert exact.ok and exact.weight_deviation == 0.0  # this machine reproduces its own data
    expected = _nudge_all(store, sid)
    assert 0 < expected < WEIGHT_TOLERANCE
    report = replay_session(store, sid, rig, mhash, model=ict_model)
    assert report.mismatches == [] and report.ok
    assert report.faces == 130 and report.weight_deviation == expected
    with store.write() as db:  # one weight of one face of the first generation moved by 1e-6
        face = _session_faces(db, sid)[3]
        w = json.loads(face.weights)
        w[5] += 1e-6
        face.weights = json.dumps(w)
        position = face.position
    report = replay_session(store, sid, rig, mhash, model=ict_model)
    assert not report.ok and len(report.mismatches) == 1, report.mismatches
    assert (
        f"generation 0, position {position}: weights differ by up to 1e-06"
        in (report.mismatches[0])
    )
    assert report.weight_deviation == pytest.approx(1e-6, rel=1e-6)


def test_the_cli_says_how_far_replay_was_from_the_recording(recorded: Any, ict_dir: Path) -> None:
    store, sid = recorded
    expected = _nudge_all(store, sid)
    app = typer.Typer()
    app.command("replay")(replay_command)
    app.command("other")(lambda: None)
    args = ["replay", str(sid), "--database-url", store.url, "--model", str(ict_dir)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "130 faces replayed: every face matches" in result.output
    assert f"largest weight deviation {expected:.3g}" in result.output
    result = CliRunner().invoke(app, [*args, "--json"])
    data = json.loads(result.output)
    assert data["weight_deviation"] == expected and data["weight_tolerance"] == WEIGHT_TOLERANCE


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_an_export_off_by_a_few_ulps_replays_and_1e6_does_not(
    recorded: Any, tmp_path: Path, ict_model, fmt: str
) -> None:
    store, sid = recorded
    out = tmp_path / fmt
    write_export(export_tables(store), out, fmt)
    path = out / f"faces.{fmt}"
    faces = pd.read_parquet(path) if fmt == "parquet" else pd.read_csv(path)
    mine = faces["session_id"] == sid
    w_cols = [c for c in faces.columns if c.startswith("w_")]
    old = faces.loc[mine, w_cols].to_numpy(float)
    new = np.vectorize(ulps_up)(old)
    expected = max(scaled(a, b) for a, b in zip(old.ravel(), new.ravel(), strict=True))
    faces.loc[mine, w_cols] = new

    def save_and_replay() -> Any:
        faces.to_parquet(path, index=False) if fmt == "parquet" else faces.to_csv(path, index=False)
        [report] = replay_exported(
            out, ict_model.rig, ict_model.model_hash, model=ict_model, session_ids=[sid]
        )
        return report

    report = save_and_replay()
    assert report.ok and report.faces == 130, report.mismatches
    assert report.weight_deviation == expected
    first = faces.index[mine][0]
    faces.loc[first, w_cols[2]] += 1e-6
    report = save_and_replay()
    assert len(report.mismatches) == 1 and "weights differ by up to 1e-06" in report.mismatches[0]


def test_categorised_faces_off_by_a_few_ulps_match_and_1e6_does_not(mixed, ict_model) -> None:  # noqa: F811
    for participant in ("U-first", "U-second"):
        token, state = mixed.create_session(participant)
        run_to_end(state, service_caller(mixed, token))
    with mixed.store.read() as db:
        sid = db.scalar(select(SessionRow.id).where(SessionRow.participant_id == "U-second"))

    def replay() -> Any:
        return replay_session(
            mixed.store, sid, ict_model.rig, ict_model.model_hash, model=ict_model
        )

    def change(source: str, how: Any) -> float:
        with mixed.store.write() as db:
            stim = db.scalars(
                select(StimulusRow)
                .join(TrialRow)
                .where(TrialRow.session_id == sid, StimulusRow.source == source)
            ).first()
            old = json.loads(stim.weights)
            new = [how(w) for w in old]
            stim.weights = json.dumps(new)
        return max(scaled(a, b) for a, b in zip(old, new, strict=True))

    assert replay().ok
    # the own face (against the face it was made as) and a random one (re-expanded, corrected)
    expected = max(change("own", ulps_up), change("random", ulps_up))
    report = replay()
    assert report.ok and report.stimuli == 8, report.mismatches
    assert 0 < report.weight_deviation == expected <= WEIGHT_TOLERANCE
    change("random", lambda w: w + 1e-6)
    change("own", lambda w: w - 1e-6)
    text = " / ".join(replay().mismatches)
    assert "(random face): weights differ by up to 1e-06" in text
    assert "(own face): weights differ from its source face by up to 1e-06" in text


def test_weight_deviation_scales_with_magnitude_and_catches_non_numbers() -> None:
    assert weight_deviation(np.array([0.5, 200.0]), np.array([0.5, 200.0 + 2e-10])) == (
        pytest.approx(1e-12)
    )
    assert weight_deviation(np.array([0.5]), np.array([0.5 + 2e-10])) == pytest.approx(2e-10)
    assert weight_deviation(np.array([np.inf]), np.array([np.inf])) == 0.0
    assert weight_deviation(np.array([0.5]), np.array([np.nan])) == np.inf
    assert weight_deviation(np.array([np.inf]), np.array([1.0])) == np.inf
    with pytest.raises(ValueError, match=r"shape \(2,\) and \(3,\)"):
        weight_deviation(np.zeros(2), np.zeros(3))
