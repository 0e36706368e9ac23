"""The ``final_faces`` export table against a plain lookup in ``faces``; categorise trials make no
face (``final_face_id`` and ``emotion`` NA in ``trials``); the tables named by their task."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from emogen import columns as tidy
from emogen.analysis.study_export import derive_final_faces
from emogen.errors import ConfigError
from emogen.study.export import FORMERLY, TABLES, export_tables, write_export
from emogen.study.export_stream import check_table_names, export_study
from emogen.study.tables import SCHEMA_VERSION
from tests.export_helpers import MIXED, simulated_tables
from tests.study.drive import do, new_key, run_to_end, service_caller
from tests.study.test_export_replay import completed


@pytest.fixture
def db_url(tmp_path: Path) -> str:
    """One backend: the table is made from the records read, whichever database holds them."""
    return f"sqlite:///{tmp_path / 'study.sqlite'}"


def plain_final_face(faces: list[dict[str, Any]], trial: dict[str, Any]) -> dict[str, Any]:
    """The trial's final face by hand: same session and trial, the last attempt, its
    ``final_face_id``, the latest generation that shows that id."""
    last_attempt = trial["attempts"] - 1
    found = [
        f
        for f in faces
        if f["study"] == trial["study"]
        and f["session_id"] == trial["session_id"]
        and f["trial"] == trial["trial"]
        and f["attempt"] == last_attempt
        and f["face_id"] == trial["final_face_id"]
    ]
    assert found, trial
    return max(found, key=lambda f: f["generation"])


def check_final_faces(tables: dict[str, pd.DataFrame]) -> int:
    """Every finished evolve trial has one ``final_faces`` row, equal to the plain lookup."""
    faces = tables["faces"].to_dict("records")
    trials = tables["trials"].to_dict("records")
    finished = [t for t in trials if t["task"] == "evolve" and t["status"] == "done"]
    final = tables["final_faces"].set_index(["session_id", "trial"])
    assert len(final) == len(finished) and final.index.is_unique
    face_columns = [c for c in tables["faces"].columns if c.startswith(("g_", "w_"))]
    assert face_columns and face_columns == [
        c for c in tables["final_faces"].columns if c.startswith(("g_", "w_"))
    ]
    for t in finished:
        want = plain_final_face(faces, t)
        got = final.loc[(t["session_id"], t["trial"])]
        for col in ("study", "participant_id", "attempt", "generation", "face_id"):
            assert got[col] == want[col], (t["session_id"], t["trial"], col)
        for col in ("block", "block_name", "emotion", "identity", "repetition", "finished_at"):
            assert got[col] == t[col], (t["session_id"], t["trial"], col)
        assert got["face_id"] == t["final_face_id"]
        for col in face_columns:  # the same numbers, bit for bit
            assert got[col] == want[col] or (pd.isna(got[col]) and pd.isna(want[col])), col
    return len(finished)


def test_final_faces_are_the_faces_a_plain_lookup_finds(service, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    completed(service, "F-1", restart=True)  # trial 0's final face is in attempt 1
    completed(service, "F-2")
    token, _ = service.create_session("F-3")  # stops at generation 1: no final face
    state = do(service, "begin", token, new_key())
    run_to_end(
        state,
        service_caller(service, token),
        stop=lambda s: s["view"] is not None and s["view"].get("generation") == 1,
    )
    tables = export_tables(service.store)
    assert check_final_faces(tables) == 4
    final = tables["final_faces"]
    assert set(final["participant_id"]) == {"F-1", "F-2"}
    assert final.query("participant_id == 'F-1' and trial == 0")["attempt"].tolist() == [1]
    # face ids restart in every trial (so the final id names faces of other trials too) and
    # run on through a trial's attempts and generations (one face, one id, within a trial)
    faces = tables["faces"]
    assert not faces.duplicated(["session_id", "trial", "face_id"]).any()
    by_id_alone = tables["trials"].merge(faces, left_on="final_face_id", right_on="face_id")
    assert len(by_id_alone) > 2 * len(final)  # a face of every trial that used the number
    # an old export's derivation gives the same rows
    derived = derive_final_faces(tables["trials"], tables["faces"])
    mine = final[derived.columns].reset_index(drop=True)
    pd.testing.assert_frame_equal(derived, mine, check_dtype=False)
    # written as Parquet and CSV, read back with the same types and values; and streamed
    for fmt in ("parquet", "csv"):
        write_export(tables, tmp_path / fmt, fmt)
        export_study(service.store, tmp_path / f"stream-{fmt}", fmt)
        for folder in (tmp_path / fmt, tmp_path / f"stream-{fmt}"):
            path = folder / f"final_faces.{fmt}"
            back = pd.read_parquet(path) if fmt == "parquet" else tidy.read_csv(path)
            pd.testing.assert_frame_equal(back, final, check_like=False)
    assert (final["schema_version"] == SCHEMA_VERSION).all()


def test_categorise_trials_make_no_face_and_name_no_emotion(tmp_path: Path, ict_model: Any) -> None:
    tables = simulated_tables(tmp_path, ict_model, MIXED, participants=4, seed=1)
    trials = tables["trials"]
    categorise = trials[trials["task"] == "categorise"]
    evolve = trials[trials["task"] == "evolve"]
    assert len(categorise) and len(evolve)
    # NA, never 0 (a real evolve face id) or the face's intended emotion
    assert categorise["final_face_id"].isna().all() and categorise["emotion"].isna().all()
    assert evolve["final_face_id"].notna().all() and evolve["emotion"].notna().all()
    # the intended emotion of a categorise face is in its own table
    responses = tables["categorise_responses"]
    assert len(responses) == len(categorise) and responses["intended"].notna().any()
    # an own face names its source trial: its final face is that trial's final_faces row
    assert check_final_faces(tables) == len(evolve)
    own = responses[responses["source"] == "own"]
    source = own.merge(
        tables["final_faces"],
        left_on=["study", "source_session_id", "source_trial"],
        right_on=["study", "session_id", "trial"],
        suffixes=("", "_source"),
    )
    assert len(source) == len(own) > 0
    assert (source["source_face_id"] == source["face_id"]).all()
    assert (source["intended"] == source["emotion"]).all()
    w = [c for c in responses.columns if c.startswith("w_")]
    assert np.allclose(
        source[w].to_numpy(float), source[[f"{c}_source" for c in w]].to_numpy(float)
    )


def test_tables_are_named_by_their_task() -> None:
    assert FORMERLY == {"ratings": "evolve_ratings", "responses": "categorise_responses"}
    assert not set(FORMERLY) & set(TABLES)
    assert {"final_faces", "evolve_ratings", "categorise_responses"} <= set(TABLES)
    check_table_names(["final_faces", "evolve_ratings"])
    with pytest.raises(ConfigError, match="'ratings' is called 'evolve_ratings' since schema"):
        check_table_names(["ratings"])
    with pytest.raises(ConfigError, match="--table must be one of sessions, trials"):
        check_table_names(["ratingz"])
