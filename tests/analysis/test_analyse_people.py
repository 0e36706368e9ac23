"""``emogen analyse`` on a real (simulated) study export: the analyses of participants, with a
participant table, and what it says when the design cannot support one."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.distance import cosine
from typer.testing import CliRunner

from emogen.cli.app import app
from emogen.study.config import study_from_dict
from emogen.study.export import export_tables, write_export
from emogen.study.simulate import SimulationPlan, simulate_study
from emogen.study.storage import Store
from emogen.tasks.simulated import SimulatedDesign

STUDY: dict[str, Any] = {
    "name": "people",
    "seed": 5,
    "emotions": ["happy", "sad"],
    "identities": ["generic"],
    "repetitions": 2,
    "ga": {"generations": 4, "min_selections": 1, "max_selections": 5},
}


def _export(root: Path, model: Any, n: int, study: dict[str, Any]) -> Path:
    url = f"sqlite:///{root / 'study.sqlite'}"
    plan = SimulationPlan(
        study_from_dict(study),
        url,
        seed=1,
        participants=n,
        design=SimulatedDesign(),
        shuffle_prototypes=False,
    )
    simulate_study(plan, model=model)
    store = Store(url)
    try:
        write_export(export_tables(store), root / "export")
    finally:
        store.dispose()
    return root / "export"


@pytest.fixture(scope="module")
def export(ict_model, tmp_path_factory: pytest.TempPathFactory) -> Path:  # type: ignore[no-untyped-def]
    return _export(tmp_path_factory.mktemp("people"), ict_model, 12, STUDY)


def _analyse(export: Path, out: Path, *extra: str) -> Any:
    return CliRunner().invoke(
        app,
        ["analyse", str(export), "--out", str(out), "--no-render", "--noise-runs", "20", *extra],
    )


def test_reliability_and_groups_with_the_participant_as_unit(
    export: Path, ict_dir: Path, tmp_path: Path
) -> None:
    table = tmp_path / "participants.csv"
    ids = [f"sim-{i + 1:04d}" for i in range(12)]
    pd.DataFrame({"participant_id": ids, "group": ["a", "b"] * 6, "age": range(20, 32)}).to_csv(
        table, index=False
    )
    out = tmp_path / "report"
    result = _analyse(export, out, "--participants", str(table), "--model", str(ict_dir))
    assert result.exit_code == 0, result.output
    rel = pd.read_csv(out / "tables" / "reliability.csv")
    assert set(rel["space"]) == {"ed", "cd", "vertex_rms"}
    assert (rel["participants"] == 12).all() and (rel["faces"] == 24).all()
    # the ICC in ED space by a plain computation on the exported faces
    faces = pd.read_parquet(export / "faces.parquet")
    trials = pd.read_parquet(export / "trials.parquet")
    from emogen.model import load_model

    for emotion in ("happy", "sad"):
        done = trials[(trials["emotion"] == emotion) & (trials["status"] == "done")]
        g, who, w = [], [], []
        shape_names = set(load_model(ict_dir).shape_names)
        for t in done.itertuples():
            f = faces[
                (faces["session_id"] == t.session_id)
                & (faces["trial"] == t.trial)
                & (faces["face_id"] == t.final_face_id)
            ]
            f = f[f["attempt"] == f["attempt"].max()]
            f = f[f["generation"] == f["generation"].max()]
            g.append(f[[c for c in f.columns if c.startswith("g_")]].to_numpy(dtype=float)[0])
            shapes = [c for c in f.columns if c.removeprefix("w_") in shape_names]
            w.append(f[shapes].to_numpy(dtype=float)[0])
            who.append(t.participant_id)
        x, who_a = np.array(g), np.array(who)
        means = {p: x[who_a == p].mean(0) for p in set(who)}
        ssw = sum(np.sum((x[who_a == p] - m) ** 2) for p, m in means.items())
        sst = np.sum((x - x.mean(0)) ** 2)
        s2w = ssw / (24 - 12)
        s2b = ((sst - ssw) / 11 - s2w) / 2
        row = rel[(rel["emotion"] == emotion) & (rel["space"] == "ed")].iloc[0]
        assert row["icc"] == pytest.approx(s2b / (s2b + s2w))
        assert row["icc_low"] < row["icc"] < row["icc_high"]
        # the spread test's empirical null: within- and between-person CD by a plain loop
        # over the shape weights (repeated faces of one participant against two participants)
        emp = pd.read_csv(out / "tables" / "spread_empirical.csv").set_index("group")
        d = [(cosine(w[a], w[b]), who[a] == who[b]) for a in range(24) for b in range(a + 1, 24)]
        within = np.mean([v for v, same in d if same])
        between = np.mean([v for v, same in d if not same])
        assert emp.loc[emotion, "within_cd"] == pytest.approx(within)
        assert emp.loc[emotion, "between_cd"] == pytest.approx(between)
        assert emp.loc[emotion, "participants"] == 12 and emp.loc[emotion, "faces"] == 24
        lo, hi = emp.loc[emotion, ["excess_ci_low", "excess_ci_high"]]
        assert lo < emp.loc[emotion, "excess_between_variance"] < hi
    groups = pd.read_csv(out / "tables" / "participant_groups.csv")
    assert list(groups["emotion"]) == ["happy", "sad"] and (groups["participants"] == 12).all()
    readme = (out / "README.md").read_text()
    assert "Unit: the participant" in readme and "one final face per participant" in readme
    summary = json.loads((out / "analysis.json").read_text())
    assert summary["participants"] == 12
    # the methods block: version, model hash, the study's config hash, command, seed
    methods = summary["methods"]
    study = pd.read_parquet(export / "study.parquet")
    assert methods["study_config_hashes"] == sorted(set(study["study_config_hash"]))
    assert methods["model_matches"] and methods["seed"] == 1
    assert "**Methods.** EmoGen" in readme and methods["model"]["hash"] in readme
    # 48 faces, a 2-group mixture in 2 dimensions has 11 parameters: fewer than 5 faces each
    assert "Warning: 48 faces for a 2-component mixture with 11 parameters" in readme
    # every face table the report writes reads in every command that reads faces
    from emogen.cli.correct import read_weights_csv as correct_reads
    from emogen.render.weights import read_weights_csv as render_reads

    model = load_model(ict_dir)
    protos = out / "tables" / "prototypes.csv"
    w, _ = render_reads(protos, model.rig)
    w2, _ = correct_reads(protos, model)
    table = pd.read_csv(protos)
    assert len(w) == len(table) == 24 and np.allclose(w, w2)
    shapes = [c for c in table.columns if c.removeprefix("w_") in model.rig.shape_names]
    assert np.allclose(w, table[shapes].to_numpy())


def test_a_wrong_participant_table_is_refused_before_any_work(export: Path, tmp_path: Path) -> None:
    short = tmp_path / "short.csv"
    pd.DataFrame({"participant_id": ["sim-0001"], "group": ["a"]}).to_csv(short, index=False)
    result = _analyse(export, tmp_path / "r1", "--participants", str(short))
    assert result.exit_code == 2
    assert "lacks 11 participant(s)" in result.output and "'sim-0002'" in result.output
    assert not (tmp_path / "r1").exists()
    nogroup = tmp_path / "nogroup.csv"
    pd.DataFrame({"participant_id": [f"sim-{i + 1:04d}" for i in range(12)]}).to_csv(
        nogroup, index=False
    )
    result = _analyse(export, tmp_path / "r2", "--participants", str(nogroup))
    assert result.exit_code == 2 and "no column 'group'" in result.output
    result = _analyse(export, tmp_path / "r3", "--participants", str(tmp_path / "absent.csv"))
    assert result.exit_code == 2 and "does not exist" in result.output


def test_one_repetition_says_why_there_is_no_reliability(
    ict_model: Any, ict_dir: Path, tmp_path: Path
) -> None:
    export = _export(tmp_path, ict_model, 4, STUDY | {"repetitions": 1})
    out = tmp_path / "report"
    result = _analyse(export, out, "--model", str(ict_dir))
    assert result.exit_code == 0, result.output
    readme = (out / "README.md").read_text()
    assert "No reliability: every participant made each emotion on each identity once" in readme
    assert not (out / "tables" / "reliability.csv").exists()


def test_wrong_exclusion_changes_are_named(export: Path, tmp_path: Path) -> None:
    result = _analyse(export, tmp_path / "r", "--exclusion", "min_rt=5")
    assert result.exit_code == 2 and "KEY one of min_median_rt_ms" in result.output
    assert "'min_rt=5'" in result.output
    result = _analyse(export, tmp_path / "r", "--exclusion", "min_median_rt_ms=fast")
    assert result.exit_code == 2 and "min_median_rt_ms needs a number or 'none'" in result.output
    result = _analyse(export, tmp_path / "r", "--exclusion", "max_same_tile_share=2")
    assert result.exit_code == 2 and "must be a share in [0, 1]; got 2.0" in result.output
    assert not (tmp_path / "r").exists()


def test_a_pilot_where_no_trial_finished_is_reported_not_a_traceback(
    export: Path, ict_dir: Path, tmp_path: Path
) -> None:
    import shutil

    pilot = tmp_path / "pilot"
    shutil.copytree(export, pilot)
    trials = pd.read_parquet(pilot / "trials.parquet")
    trials["status"] = "started"
    trials["final_face_id"] = None
    trials.to_parquet(pilot / "trials.parquet")
    out = tmp_path / "report"
    result = _analyse(pilot, out, "--model", str(ict_dir))
    assert result.exit_code == 0, result.output
    readme = (out / "README.md").read_text()
    assert "No errors: no group has a complete sample" in readme
    assert "None: no GA trial is finished" in readme


def test_a_study_of_categorise_blocks_only_is_analysed(
    ict_model: Any, ict_dir: Path, tmp_path: Path
) -> None:
    """A stimulus-validation study (raters label random faces): no GA trial at all."""
    study = {
        "name": "validation",
        "seed": 3,
        "emotions": ["happy", "sad"],
        "identities": ["generic"],
        "blocks": [{"task": "categorise", "random": 6}],
    }
    export = _export(tmp_path, ict_model, 3, study)
    out = tmp_path / "report"
    result = _analyse(export, out, "--model", str(ict_dir))
    assert result.exit_code == 0, result.output
    readme = (out / "README.md").read_text()
    assert "None: the export has no GA trial" in readme
    assert "## Categorisation of faces" in readme


def test_an_export_written_before_final_faces_analyses_the_same(
    export: Path, ict_dir: Path, tmp_path: Path
) -> None:
    """Schema 5 (no final_faces; ratings and responses under their old names): every figure and
    table of ``emogen analyse`` is the same as the new export's."""
    from tests.export_helpers import as_schema5

    old = as_schema5(export, tmp_path / "export-old")
    reports = {}
    for name, folder in (("new", export), ("old", old)):
        result = _analyse(folder, tmp_path / name, "--model", str(ict_dir))
        assert result.exit_code == 0, result.output
        summary = json.loads((tmp_path / name / "analysis.json").read_text())
        for key in ("source", "methods"):  # they name the folder and the command line
            summary.pop(key)
        reports[name] = summary
    assert reports["new"] == reports["old"]
    tables = sorted(p.name for p in (tmp_path / "new" / "tables").iterdir())
    assert "ratings.csv" in tables and "reliability.csv" in tables
    for name in tables:
        new, old_table = (tmp_path / d / "tables" / name for d in ("new", "old"))
        assert new.read_bytes() == old_table.read_bytes(), name
