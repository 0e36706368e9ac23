"""An evolve block with ``dynamic`` faces: piloted through the real service, recorded (curves
beside the faces), exported and replayed; tampered curves are caught; static blocks as before."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.cli import app
from emogen.errors import ConfigError
from emogen.study.config import study_from_dict

STUDY = """
name = "dyn"
seed = 5
emotions = ["happy", "sad"]
ga = {{ generations = 2, min_selections = 1, max_selections = 3 }}
model = "{model}"

[[blocks]]
task = "evolve"
dynamic = {{ clip_s = 1.5, keyframes = 9 }}

[[blocks]]
task = "evolve"
"""


@pytest.fixture(scope="module")
def piloted(tmp_path_factory: pytest.TempPathFactory, ict_dir: Path) -> tuple[str, Path, Path]:
    tmp = tmp_path_factory.mktemp("dynamic")
    config = tmp / "dyn.toml"
    config.write_text(STUDY.format(model=ict_dir))
    db = tmp / "dyn.sqlite"
    url = f"sqlite:///{db}"
    run = CliRunner().invoke
    result = run(app, ["study", "simulate", str(config), "-n", "2", "--seed", "4",
                       "--database-url", url])  # fmt: skip
    assert result.exit_code == 0, result.output
    out = tmp / "export"
    result = run(app, ["study", "export", "--database-url", url, "--out", str(out),
                       "--format", "csv"])  # fmt: skip
    assert result.exit_code == 0, result.output
    return url, db, out


def replay(url: str) -> dict:  # type: ignore[type-arg]
    result = CliRunner().invoke(app, ["replay", "1", "--database-url", url, "--json"])
    return dict(json.loads(result.output), exit_code=result.exit_code)


def test_dynamic_trials_record_their_curves_and_static_trials_do_not(piloted) -> None:
    _, db, _ = piloted
    with sqlite3.connect(db) as con:
        trials = pd.read_sql("SELECT id, block, engine_state FROM trials", con)
        curves = pd.read_sql(
            "SELECT c.*, p.trial_id FROM face_curves c JOIN populations p ON p.id = c.population_id",
            con,
        )
        faces = pd.read_sql(
            "SELECT f.genes, p.trial_id FROM faces f JOIN populations p ON p.id = f.population_id",
            con,
        )
    dynamic = trials[trials.block == 0]
    static = trials[trials.block == 1]
    assert set(curves.trial_id) == set(dynamic.id)  # every dynamic face, no static one
    assert len(curves) == faces.trial_id.isin(dynamic.id).sum()
    for state in dynamic.engine_state:
        assert json.loads(state)["genome"]["clip_s"] == 1.5
    for state in static.engine_state:
        assert "genome" not in json.loads(state)
    timing = np.array(json.loads(curves.timing.iloc[0]))
    keyed = np.array(json.loads(curves.keyframe_correctives.iloc[0]))
    genes = np.array(json.loads(faces.genes.iloc[0]))
    assert timing.shape == (len(genes), 5) and ((timing >= 0) & (timing <= 1)).all()
    assert keyed.shape[0] == 9 and keyed[0].max() == 0  # a clip starts at rest


def test_a_dynamic_study_replays_exactly_and_tampered_curves_are_caught(piloted, tmp_path) -> None:
    url, db, _ = piloted
    report = replay(url)
    assert report["ok"] is True and report["exit_code"] == 0 and report["populations"] == 12
    copy = tmp_path / "tampered.sqlite"
    copy.write_bytes(db.read_bytes())
    with sqlite3.connect(copy) as con:
        row = con.execute("SELECT id, timing FROM face_curves ORDER BY id LIMIT 1").fetchone()
        timing = json.loads(row[1])
        timing[0][2] = 1.0 - timing[0][2]  # the first gene's peak latency
        con.execute("UPDATE face_curves SET timing = ? WHERE id = ?", (json.dumps(timing), row[0]))
        row = con.execute(
            "SELECT id, keyframe_correctives FROM face_curves ORDER BY id LIMIT 1 OFFSET 1"
        ).fetchone()
        keyed = json.loads(row[1])
        keyed[4][0] += 0.25
        con.execute(
            "UPDATE face_curves SET keyframe_correctives = ? WHERE id = ?",
            (json.dumps(keyed), row[0]),
        )
    report = replay(f"sqlite:///{copy}")
    assert report["ok"] is False and report["exit_code"] != 0
    assert any(m.endswith("position 0: genes") for m in report["mismatches"])
    assert any("keyframe correctives differ by up to 0.25" in m for m in report["mismatches"])


def test_a_static_block_serialises_as_before_and_a_bad_dynamic_key_is_named(ict_dir) -> None:
    base = {"name": "s", "emotions": ["happy"], "model": str(ict_dir)}
    static = study_from_dict({**base, "blocks": [{"task": "evolve"}]})
    assert "dynamic" not in static.canonical_json()
    moving = study_from_dict({**base, "blocks": [{"task": "evolve", "dynamic": {}}]})
    assert moving.config_hash() != static.config_hash()
    with pytest.raises(ConfigError, match="clip"):
        study_from_dict({**base, "blocks": [{"task": "evolve", "dynamic": {"clip": 2}}]})
    with pytest.raises(ConfigError, match="min_segment_s must be in"):
        study_from_dict(
            {
                **base,
                "blocks": [{"task": "evolve", "dynamic": {"clip_s": 0.3, "min_segment_s": 0.2}}],
            }
        )


def test_the_curves_export_one_row_per_face_per_gene_shown(piloted) -> None:
    _, db, out = piloted
    table = pd.read_csv(out / "face_curves.csv")
    faces = pd.read_csv(out / "faces.csv")
    with sqlite3.connect(db) as con:  # the database itself, read without EmoGen
        stored = pd.read_sql(
            "SELECT p.trial_id, t.position AS trial, t.session_id, p.attempt, p.generation, "
            "c.position, c.timing, f.genes, f.face_id FROM face_curves c "
            "JOIN populations p ON p.id = c.population_id JOIN trials t ON t.id = p.trial_id "
            "JOIN faces f ON f.population_id = c.population_id AND f.position = c.position",
            con,
        )
    expected = sum(int((np.array(json.loads(g)) > 0).sum()) for g in stored.genes)
    assert len(table) == expected > 0
    genes = [c[2:] for c in faces.columns if c.startswith("g_")]
    row = stored.iloc[7]
    amp, timing = np.array(json.loads(row.genes)), np.array(json.loads(row.timing))
    mine = table[
        (table.session_id == row.session_id)
        & (table.trial == row.trial)
        & (table.generation == row.generation)
        & (table.position == row.position)
    ]
    assert list(mine.gene) == [genes[k] for k in np.flatnonzero(amp > 0)]
    for _, r in mine.iterrows():
        k = genes.index(r.gene)
        assert r.amplitude == amp[k]
        assert list(r[["onset", "acceleration", "peak", "deceleration", "offset"]]) == list(
            timing[k]
        )
    d, s = 1.5, 0.08  # the block's clip and shortest segment: latencies from docs/ga.md
    onset = table.onset * (d - 2 * s)
    peak = onset + s + table.peak * (d - 2 * s - onset)
    offset = peak + s + table.offset * (d - s - peak)
    np.testing.assert_allclose(table.onset_s, onset, rtol=1e-12)
    np.testing.assert_allclose(table.peak_s, peak, rtol=1e-12)
    np.testing.assert_allclose(table.offset_s, offset, rtol=1e-12)
    assert (table.clip_s == 1.5).all()


def test_the_curves_read_in_r_with_their_types(piloted, rscript) -> None:
    from tests.r_readers import col_types_of, read_in_r

    _, _, out = piloted
    types = col_types_of(out)
    table = read_in_r([out / "face_curves.csv"], types)[0]
    assert len(table.frame) == len(pd.read_csv(out / "face_curves.csv")) > 0
    assert table.classes["gene"] == "character"
    for column in ("face_id", "amplitude", "onset", "peak_s", "offset_s", "clip_s"):
        assert table.classes[column] == "numeric", column


def test_a_dynamic_study_replays_from_its_export(piloted, tmp_path) -> None:
    _, _, out = piloted
    run = CliRunner().invoke
    result = run(app, ["replay", "1", "--from-export", str(out), "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.output)[0]
    assert report["ok"] is True and report["populations"] == 12 and report["faces"] == 120
    copy = tmp_path / "export"
    copy.mkdir()
    for f in out.iterdir():
        (copy / f.name).write_bytes(f.read_bytes())
    faces = pd.read_csv(copy / "faces.csv")
    gene = next(c for c in faces.columns if c.startswith("g_"))
    faces.loc[3, gene] = 1.0 - faces.loc[3, gene]  # a dynamic face's amplitude
    faces.to_csv(copy / "faces.csv", index=False)
    result = run(app, ["replay", "1", "--from-export", str(copy), "--json"])
    report = json.loads(result.output)[0]
    assert result.exit_code != 0 and report["ok"] is False
    assert any("position 3: genes" in m for m in report["mismatches"])


def test_a_dynamic_block_is_checked_and_served(
    ict_dir: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The page plays moving faces (tests/web/test_dynamic_browser.py): a dynamic block passes
    ``study check`` and the server starts. A block a task says participants cannot be shown
    (``TaskBlock.unservable``) is still an error there and refused by the server, by name."""
    from emogen.study.check import check_study
    from emogen.tasks.evolve.block import EvolveBlock
    from emogen.web import create_app

    config = tmp_path / "dyn.toml"
    config.write_text(STUDY.format(model=ict_dir))
    result = CliRunner().invoke(app, ["study", "check", str(config)])
    assert result.exit_code == 0 and "0 errors, 0 warnings: ready" in result.output, result.output
    moving = study_from_dict(
        {"name": "d", "emotions": ["happy"], "model": str(ict_dir),
         "blocks": [{"task": "evolve"}, {"task": "evolve", "dynamic": {}}]}
    )  # fmt: skip
    assert [f for f in check_study(moving).findings if f.level == "error"] == []
    served = create_app(moving, f"sqlite:///{tmp_path / 'd.sqlite'}")
    served.state.store.dispose()

    def unservable(self: EvolveBlock) -> str | None:
        return None if self.dynamic is None else "dynamic: not yet shown to participants"

    monkeypatch.setattr(EvolveBlock, "unservable", unservable)
    errors = [f for f in check_study(moving).findings if f.level == "error"]
    assert [f.where for f in errors] == ["blocks[2]"]
    with pytest.raises(ConfigError, match=r"blocks\[2\]: dynamic: not yet shown"):
        create_app(moving, f"sqlite:///{tmp_path / 'e.sqlite'}")
    assert not (tmp_path / "e.sqlite").exists()  # refused before a database was made
