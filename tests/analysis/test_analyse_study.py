"""End to end: participants go through a study (the study server's library), the export is
written, and `emogen analyse` reads it.

Simulated participants drive :class:`~emogen.study.sessions.StudyService` exactly as the web
pages do (begin, select, restart, rate): each picks the faces closest by CD to their own
target for the emotion asked, so the export has real structure — happy and sad faces that a
GMM can tell apart. One participant restarts a trial, one stops half way.
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.cli.analysis import analysis_app
from emogen.metrics import cosine_distance
from tests.study.drive import do

STUDY: dict[str, Any] = {
    "name": "analysis-e2e",
    "emotions": ["happy", "sad"],
    "seed": 7,
    "order": "fixed",
    "ga": {"generations": 3, "min_selections": 1, "max_selections": 5},
}
PARTICIPANTS = 8
_keys = itertools.count()


def key() -> str:
    return f"analysis-e2e-{next(_keys):06d}"


def drive(
    service: Any,
    participant: str,
    targets: dict[str, np.ndarray],
    *,
    restart: bool = False,
    stop_after: int | None = None,
) -> None:
    token, _ = service.create_session(participant)
    state = do(service, "begin", token, key())
    steps = 0
    while state["stage"] != "done":
        if stop_after is not None and steps >= stop_after:
            return
        progress, trial, view = state["progress"], state["trial"], state["view"]
        at = {
            "trial": progress["trial"],
            "attempt": trial["attempt"],
            "generation": view["generation"],
        }
        if trial["status"] == "active":
            if (
                restart
                and progress["trial"] == 0
                and trial["attempt"] == 0
                and view["generation"] == 1
            ):
                state = do(service, "restart", token, key(), **at)
                continue
            faces = state["view"]["population"]["faces"]
            w = np.array([f["weights"] for f in faces])[:, : len(targets[view["emotion"]])]
            order = np.argsort(cosine_distance(w, targets[view["emotion"]]), kind="stable")
            ids = [faces[i]["id"] for i in order]
            state = do(
                service,
                "select",
                token,
                key(),
                **at,
                elite=ids[0],
                others=ids[1:3],
                response_ms=900.0,
            )
        else:
            state = do(
                service, "rate", token, key(), trial=progress["trial"], value=5, response_ms=500.0
            )
        steps += 1


@pytest.fixture(scope="module")
def export(ict_model, tmp_path_factory: pytest.TempPathFactory) -> Path:  # type: ignore[no-untyped-def]
    from emogen.analysis.paper_targets import participant_target
    from emogen.study.config import study_from_dict
    from emogen.study.export import export_tables, write_export
    from emogen.study.sessions import StudyService
    from emogen.study.storage import Store

    root = tmp_path_factory.mktemp("study")
    store = Store(f"sqlite:///{root / 'study.sqlite'}")
    service = StudyService(
        study_from_dict(STUDY),
        store,
        ict_model.rig,
        model_name=ict_model.name,
        model_hash=ict_model.model_hash,
        model=ict_model,
    )
    rng = np.random.default_rng(11)
    rig = ict_model.rig
    for p in range(PARTICIPANTS):
        targets = {
            e: rig.weights_from_names(participant_target(rig, e, rng=rng)) for e in ("happy", "sad")
        }
        drive(service, f"P-{p:02d}", targets, restart=p == 1)
    drive(
        service,
        "P-quit",
        {e: rig.weights_from_names({"mouthSmile": 1.0}) for e in ("happy", "sad")},
        stop_after=2,
    )
    tables = export_tables(store)
    write_export(tables, root / "export", "parquet")
    write_export(tables, root / "export-csv", "csv")
    store.dispose()
    return root


def test_analyse_a_study_export(export: Path, ict_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "report"
    config = tmp_path / "study.toml"
    config.write_text(
        'name = "analysis-e2e"\nemotions = ["happy", "sad"]\n'
        "[ga]\ngenerations = 3\nmin_selections = 1\nmax_selections = 5\n"
    )
    result = CliRunner().invoke(
        analysis_app,
        [
            "analyse",
            str(export / "export"),
            "--out",
            str(out),
            "--model",
            str(ict_dir),
            "--noise-runs",
            "100",
            "--config",
            str(config),
        ],
    )
    assert result.exit_code == 0, result.output
    assert (out / "index.html").is_file() and (out / "README.md").is_file()
    summary = json.loads((out / "analysis.json").read_text())
    assert summary["kind"] == "study" and summary["groups"] == ["happy", "sad"]
    # 8 complete participants per emotion; the one who quit (incomplete) is excluded by the
    # default rule (fewer than 75% of GA trials finished), before every analysis
    assert summary["samples"] == {"happy": 8, "sad": 8}
    assert "P-quit" in (out / "README.md").read_text().split("excluded by the rule above")[1][:200]
    elites = pd.read_csv(out / "tables" / "elites.csv")
    assert elites["complete"].sum() == 2 * PARTICIPANTS * 4  # generations 0..3 of 16 trials
    # after a restart only the last attempt counts: still 4 generations for that trial
    p1 = elites[(elites["participant"] == "P-01") & (elites["group"] == "happy")]
    assert sorted(p1["generation"]) == [0, 1, 2, 3]
    protos = pd.read_csv(out / "tables" / "prototypes.csv")
    assert len(protos) == 2 * PARTICIPANTS and (protos["n_trials"] == 1).all()
    assert "P-quit" not in set(protos["participant"])
    # happy and sad participants' final faces separate
    assert summary["separability"]["accuracy"] >= 0.85
    errors = pd.read_csv(out / "tables" / "errors_by_generation.csv")
    assert set(errors["generation"]) == {0, 1, 2, 3}
    happy = errors[errors["group"] == "happy"].set_index("generation")["mean"]
    assert happy.loc[3] < happy.loc[0]  # elites approach the group's mean face
    rep = pd.read_csv(out / "tables" / "repeatability.csv")
    assert rep.filter(like="pct_pairs_cd_").sum(axis=1).round(6).eq(100).all()
    spread = pd.read_csv(out / "tables" / "spread_test.csv")
    assert set(spread["group"]) == {"happy", "sad"}
    ratings = pd.read_csv(out / "tables" / "ratings.csv")
    assert ratings["mean"].eq(5).all()
    assert (out / "figures" / "mean_face_heatmaps.png").is_file()
    # the study corrected its faces: correctives follow the shapes in the weights
    assert any(c.startswith("w_corr_") for c in elites.columns)
    assert "correctives are left out" in (out / "README.md").read_text()


def test_analyse_reads_the_csv_export_too(export: Path, tmp_path: Path) -> None:
    from emogen.analysis.data import load_dataset

    a, b = load_dataset(export / "export"), load_dataset(export / "export-csv")
    assert a.groups == b.groups and a.columns == b.columns
    pd.testing.assert_frame_equal(
        a.elites.reset_index(drop=True), b.elites.reset_index(drop=True), check_dtype=False
    )


def test_analyse_a_one_participant_export(ict_model, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """Like the browser test's export: one participant, one generation, a restart. What needs
    several faces is skipped with a reason; the rest is reported."""
    from emogen.analysis.analyse import AnalysisOptions, analyse
    from emogen.study.config import study_from_dict
    from emogen.study.export import export_tables, write_export
    from emogen.study.sessions import StudyService
    from emogen.study.storage import Store

    store = Store(f"sqlite:///{tmp_path / 'one.sqlite'}")
    cfg = dict(STUDY) | {
        "name": "one",
        "ga": {"generations": 1, "min_selections": 2, "max_selections": 3},
    }
    service = StudyService(
        study_from_dict(cfg),
        store,
        ict_model.rig,
        model_name=ict_model.name,
        model_hash=ict_model.model_hash,
        model=ict_model,
    )
    smile = ict_model.rig.weights_from_names({"mouthSmile": 1.0})
    drive(service, "browser-1", {"happy": smile, "sad": smile}, restart=True)
    write_export(export_tables(store), tmp_path / "export", "csv")
    store.dispose()
    res = analyse(
        tmp_path / "export",
        tmp_path / "out",
        model=ict_model,
        options=AnalysisOptions(noise_runs=50, render_size=96),
    )
    html = res.html.read_text()
    assert "Skipped: too few final faces" in html and "fewer than 2 final faces" in html
    protos = pd.read_csv(tmp_path / "out" / "tables" / "prototypes.csv")
    assert list(protos["group"]) == ["happy", "sad"]
    assert (tmp_path / "out" / "figures" / "mean_faces.png").is_file()
