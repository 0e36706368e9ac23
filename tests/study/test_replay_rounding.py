"""Replay across machines: a recording whose stored weights differ from this machine's by a few
units in the last place (another CPU's BLAS rounding) replays as matching and reports how far
apart they were; a weight moved by 1e-6 — far above rounding — is still a mismatch. For evolve
faces (from the database and from an export, and through the CLI) and for categorised faces.

The nudge is computed here with Python's ``math.nextafter`` on the stored values, independently
of the replay code. The deviation a replay reports is that nudge give or take this CPU's own
rounding of the recording (0 on the machine that recorded it, 2.2e-16 on an AMD EPYC for
``tests/data``'s study): the tests assert those bounds, never this CPU's last bits.
"""

from __future__ import annotations

import json
import math
import re
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
#: How far every stored weight is moved: well above a CPU's own rounding of a recording (up to
#: 3.3e-16, emogen.study.rounding), so that the two can be told apart, and far below tolerance.
ULPS = 16
#: A recording as another CPU would have stored it: weights one or two ULPs off this CPU's own.
OTHER_CPU_ULPS = (-2, -1, 1, 2)


def ulps_up(w: float, k: int = ULPS) -> float:
    for _ in range(k):
        w = math.nextafter(w, math.inf)
    return w


def ulps_off(w: float, k: int) -> float:
    for _ in range(abs(k)):
        w = math.nextafter(w, math.inf if k > 0 else -math.inf)
    return w


def scaled(old: float, new: float) -> float:
    return abs(new - old) / max(1.0, abs(old))


def assert_reports_the_nudge(reported: float, nudge: float, own: float) -> None:
    """``reported``: the deviation replay reports for a recording whose weights were moved by
    up to ``nudge``; ``own``: what it reported for the recording before (this CPU's rounding of
    it). Elementwise |stored + n − replayed| lies within |n| ± |stored − replayed| (the triangle
    inequality), and so do the maxima: the report is the nudge within this CPU's own rounding
    (1e-9 of the nudge to spare for the scaling by max(1, |w|), computed from the weights
    before and after the nudge), whichever CPU runs this."""
    assert 2 * own < nudge, f"this CPU's own rounding {own:.3g} hides a nudge of {nudge:.3g}"
    assert abs(reported - nudge) <= own + 1e-9 * nudge, (reported, nudge, own)
    assert reported <= WEIGHT_TOLERANCE


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


def _nudge_all(store: Store, session_id: int, how: Any = ulps_up) -> float:
    """Every stored weight of the session moved by ``how`` (a few ULPs up); the largest scaled
    change."""
    worst = 0.0
    with store.write() as db:
        for face in _session_faces(db, session_id):
            old = json.loads(face.weights)
            new = [how(w) for w in old]
            worst = max([worst, *(scaled(a, b) for a, b in zip(old, new, strict=True))])
            face.weights = json.dumps(new)
    return worst


def _recorded_copy(tmp_path: Path) -> tuple[Store, int]:
    copy = tmp_path / "recorded.sqlite"
    shutil.copyfile(RECORDED, copy)
    store = Store(f"sqlite:///{copy}")
    with store.read() as db:
        ids = {s.participant_id: s.id for s in db.scalars(select(SessionRow))}
    return store, ids["OLD-1"]


@pytest.fixture
def recorded(tmp_path: Path) -> Any:
    store, sid = _recorded_copy(tmp_path)
    yield store, sid
    store.dispose()


@pytest.fixture(params=["this-cpu", "other-cpu"])
def recorded_somewhere(request: pytest.FixtureRequest, tmp_path: Path) -> Any:
    """The recorded study as stored, and as a CPU that rounds differently would have stored it
    (a seeded choice of one or two ULPs either way, or none, per weight): the bounds must hold
    whichever machine recorded the study and whichever replays it."""
    store, sid = _recorded_copy(tmp_path)
    if request.param == "other-cpu":
        rng = np.random.default_rng(38)

        def other(w: float) -> float:
            k = int(rng.integers(0, 2 * len(OTHER_CPU_ULPS)))
            return ulps_off(w, OTHER_CPU_ULPS[k]) if k < len(OTHER_CPU_ULPS) else w

        assert 0 < _nudge_all(store, sid, other) < 1e-15
    yield store, sid
    store.dispose()


def test_a_recording_off_by_a_few_ulps_replays_and_1e6_does_not(
    recorded_somewhere: Any, ict_model
) -> None:
    store, sid = recorded_somewhere
    rig, mhash = ict_model.rig, ict_model.model_hash
    exact = replay_session(store, sid, rig, mhash, model=ict_model)
    # every face matches: this CPU's rounding of the recording (0 where it was recorded)
    assert exact.ok and exact.faces == 130 and exact.mismatches == []
    assert 0 <= exact.weight_deviation <= WEIGHT_TOLERANCE
    expected = _nudge_all(store, sid)
    assert 0 < expected < WEIGHT_TOLERANCE
    report = replay_session(store, sid, rig, mhash, model=ict_model)
    assert report.mismatches == [] and report.ok and report.faces == 130
    assert_reports_the_nudge(report.weight_deviation, expected, exact.weight_deviation)
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


def test_the_cli_says_how_far_replay_was_from_the_recording(
    recorded: Any, ict_dir: Path, ict_model
) -> None:
    store, sid = recorded
    own = replay_session(store, sid, ict_model.rig, ict_model.model_hash, model=ict_model)
    expected = _nudge_all(store, sid)
    app = typer.Typer()
    app.command("replay")(replay_command)
    app.command("other")(lambda: None)
    args = ["replay", str(sid), "--database-url", store.url, "--model", str(ict_dir)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "130 faces replayed: every face matches" in result.output
    said = re.search(r"largest weight deviation (\S+) \(", result.output)
    assert said is not None, result.output
    result = CliRunner().invoke(app, [*args, "--json"])
    data = json.loads(result.output)
    assert data["weight_tolerance"] == WEIGHT_TOLERANCE
    assert_reports_the_nudge(data["weight_deviation"], expected, own.weight_deviation)
    assert said[1] == f"{data['weight_deviation']:.3g}"  # the text says what --json says


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_an_export_off_by_a_few_ulps_replays_and_1e6_does_not(
    recorded: Any, tmp_path: Path, ict_model, fmt: str
) -> None:
    store, sid = recorded
    out = tmp_path / fmt
    write_export(export_tables(store), out, fmt)
    path = out / f"faces.{fmt}"
    faces = pd.read_parquet(path) if fmt == "parquet" else pd.read_csv(path)
    [own] = replay_exported(
        out, ict_model.rig, ict_model.model_hash, model=ict_model, session_ids=[sid]
    )
    assert own.ok and own.faces == 130, own.mismatches
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
    assert_reports_the_nudge(report.weight_deviation, expected, own.weight_deviation)
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

    before = replay()
    assert before.ok and before.stimuli == 8, before.mismatches
    # the own face (against the face it was made as) and a random one (re-expanded, corrected)
    expected = max(change("own", ulps_up), change("random", ulps_up))
    report = replay()
    assert report.ok and report.stimuli == 8, report.mismatches
    assert_reports_the_nudge(report.weight_deviation, expected, before.weight_deviation)
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
