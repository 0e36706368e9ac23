# ruff: noqa: F811  (pytest fixtures imported by name, then requested by name)
"""A GSP study end to end: ``emogen study simulate`` runs it, ``emogen study export`` writes
its tables (checked against the database read with sqlite3 and against numpy), ``emogen
replay`` rebuilds every chain from its seed and the records and names a tampered record; wrong
configs and wrong answers are refused by name and leave nothing recorded."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.cli.app import app
from emogen.errors import ConfigError, SelectionError
from emogen.study.config import study_from_dict
from emogen.study.errors import StepConflict
from emogen.study.storage import Store
from tests.r_readers import col_types_of, read_in_r, undocumented
from tests.study.drive import new_key, study_service
from tests.study_fixtures import db_url, pg_cluster  # noqa: F401

STUDY = """
name = "gsp-study"
seed = 5
emotions = ["happy", "sad"]
correct = false
model = "{model}"

[[blocks]]
task = "gsp"
chains = 3
iterations = 4
steps = 21
slider = [0.0, 0.8]
"""


@pytest.fixture(scope="module")
def piloted(tmp_path_factory: pytest.TempPathFactory, ict_dir: Path) -> dict[str, Any]:
    """Six simulated participants of the study, exported as CSV."""
    tmp = tmp_path_factory.mktemp("gsp")
    config = tmp / "gsp.toml"
    config.write_text(STUDY.format(model=ict_dir))
    db = tmp / "gsp.sqlite"
    url = f"sqlite:///{db}"
    run = CliRunner().invoke
    result = run(
        app, ["study", "simulate", str(config), "-n", "6", "--seed", "3", "--database-url", url]
    )
    assert result.exit_code == 0, result.output
    out = tmp / "export"
    result = run(
        app, ["study", "export", "--database-url", url, "--out", str(out), "--format", "csv"]
    )
    assert result.exit_code == 0, result.output
    result = run(
        app,
        ["study", "export", "--database-url", url, "--out", str(tmp / "pq"), "--format", "parquet"],
    )
    assert result.exit_code == 0, result.output
    return {"db": db, "url": url, "out": out, "pq": tmp / "pq"}


def test_the_export_holds_every_answer_as_the_database_does(piloted: dict[str, Any]) -> None:
    table = pd.read_csv(piloted["out"] / "gsp_iterations.csv")
    with sqlite3.connect(piloted["db"]) as con:  # the database itself, read without EmoGen
        stored = pd.read_sql(
            "SELECT s.participant_id, t.position AS trial, t.seed, t.emotion, c.chain, "
            "i.iteration, i.position, i.slider_value, i.slider_start, i.genes_before, "
            "i.genes_after FROM gsp_iterations i JOIN trials t ON t.id = i.trial_id "
            "JOIN sessions s ON s.id = t.session_id JOIN gsp_chains c ON c.id = i.chain_id "
            "ORDER BY s.id, t.position",
            con,
        )
    assert len(table) == len(stored) == 6 * 2 * 4  # participants × concepts × iterations
    cols = ["participant_id", "trial", "emotion", "chain", "iteration", "position"]
    assert table[cols].to_dict("records") == stored[cols].to_dict("records")
    grid = np.linspace(0.0, 0.8, 21)
    assert table["slider_value"].to_numpy() == pytest.approx(grid[table["position"]])
    starts = [int(np.random.default_rng(int(s)).integers(21)) for s in stored["seed"]]
    assert table["slider_start"].tolist() == starts
    for row, db_row in zip(table.itertuples(), stored.itertuples(), strict=True):
        before = json.loads(db_row.genes_before)
        after = [getattr(row, f"g_{g}") for g in json.loads(_gene_names(piloted["db"]))]
        moved = [i for i, (a, b) in enumerate(zip(before, after, strict=True)) if a != b]
        assert set(moved) <= {row.dimension_index}
        assert after[row.dimension_index] == pytest.approx(row.slider_value)
        assert before[row.dimension_index] == pytest.approx(row.value_before)
        assert json.loads(row.genes_before) == pytest.approx(before)


def test_the_tables_read_in_r_with_their_types_and_are_documented(
    piloted: dict[str, Any], rscript: None
) -> None:
    names = ["gsp_iterations", "gsp_chains"]
    types = col_types_of(piloted["out"])
    read = read_in_r([piloted["out"] / f"{n}.csv" for n in names], types)
    for name, table in zip(names, read, strict=True):
        ref = pd.read_parquet(piloted["pq"] / f"{name}.parquet")
        assert table.problems == 0 and len(table.frame) == len(ref), name
        assert not undocumented(list(ref.columns), f"study export: {name}"), name
        numeric = {c for c, k in table.classes.items() if k == "numeric"}
        assert numeric == {
            c
            for c in ref.columns
            if pd.api.types.is_numeric_dtype(ref[c])
            and not pd.api.types.is_bool_dtype(ref[c])
            and c != "seed"
        }, name
        for c in numeric:
            np.testing.assert_allclose(
                table.frame[c].to_numpy(dtype=float), ref[c].to_numpy(dtype=float), rtol=1e-12
            )
    assert (
        read[0].classes["applied"] == "logical" and read[0].classes["assigned_at"] == "POSIXct:UTC"
    )
    assert read[1].classes["seed"] == "character"


def _gene_names(db: Path) -> str:
    with sqlite3.connect(db) as con:
        return str(con.execute("SELECT gene_names FROM studies").fetchone()[0])


def test_chains_are_extended_node_by_node_and_kept_level(piloted: dict[str, Any]) -> None:
    """A plain loop over the exported rows: each chain's nodes 0…n-1 once each, each node
    starting where the one before ended, and one participant after another keeps the chains
    of a concept within one node of each other."""
    table = pd.read_csv(piloted["out"] / "gsp_iterations.csv")
    assert table["applied"].all() and (table["aggregation"] == 1).all()
    lengths: dict[str, list[int]] = {}
    for (emotion, _chain), rows in table.groupby(["emotion", "chain"]):
        rows = rows.sort_values("iteration")
        assert rows["iteration"].tolist() == list(range(len(rows)))
        for a, b in zip(rows.itertuples(), rows.iloc[1:].itertuples(), strict=False):
            after = json.loads(a.genes_before)
            after[a.dimension_index] = a.node_value
            assert json.loads(b.genes_before) == pytest.approx(after)
        lengths.setdefault(str(emotion), []).append(len(rows))
    assert all(max(n) - min(n) <= 1 for n in lengths.values()), lengths
    chains = pd.read_csv(piloted["out"] / "gsp_chains.csv")
    assert len(chains) == 2 * 3 and chains["seed"].str.startswith("s").all()


def test_replay_rebuilds_the_chains_and_names_a_tampered_answer(
    piloted: dict[str, Any], tmp_path: Path
) -> None:
    run = CliRunner().invoke
    copy = tmp_path / "copy.sqlite"
    copy.write_bytes(Path(piloted["db"]).read_bytes())
    url = f"sqlite:///{copy}"
    for session in ("1", "6"):
        result = run(app, ["replay", session, "--database-url", url, "--json"])
        assert result.exit_code == 0, result.output
        report = json.loads(result.output)
        assert report["ok"] is True and report["stimuli"] == 8 and report["mismatches"] == []
    with sqlite3.connect(copy) as con:  # one answer's value changed, one chain's start face
        con.execute("UPDATE gsp_iterations SET slider_value = 0.123 WHERE id = 3")
        trial = con.execute(
            "SELECT t.position FROM gsp_iterations i JOIN trials t ON t.id = i.trial_id "
            "WHERE i.id = 3"
        ).fetchone()[0]
    result = run(app, ["replay", "1", "--database-url", url, "--json"])
    report = json.loads(result.output)
    assert result.exit_code != 0 and report["ok"] is False
    assert any(
        m.startswith(f"trial {trial + 1} ") and "value 0.123" in m for m in report["mismatches"]
    ), report["mismatches"]


def _replay_export(folder: Path) -> list[dict[str, Any]]:
    result = CliRunner().invoke(app, ["replay", "--from-export", str(folder), "--json"])
    assert result.exit_code in (0, 1), result.output
    return list(json.loads(result.output))


@pytest.mark.parametrize("fmt", ["out", "pq"])
def test_an_export_replays_every_chain_with_counts(piloted: dict[str, Any], fmt: str) -> None:
    reports = _replay_export(piloted[fmt])
    table = pd.read_csv(piloted["out"] / "gsp_iterations.csv")
    per_session = table.groupby("session_id").size().to_dict()  # counted by pandas
    assert [r["session_id"] for r in reports] == sorted(per_session)
    for r in reports:
        assert r["ok"] is True and r["mismatches"] == [] and r["unchecked"] == [], r
        assert r["checked"]["gsp answers"] == per_session[r["session_id"]]
    chains = pd.read_csv(piloted["out"] / "gsp_chains.csv")
    assert sum(r["checked"].get("gsp chains", 0) for r in reports) == len(chains) == 6


def _tampered(piloted: dict[str, Any], to: Path, change: Any) -> Path:
    """A copy of the CSV export with ``change(iterations, chains)`` applied to two tables."""
    import shutil

    shutil.copytree(piloted["out"], to)
    iterations = pd.read_csv(to / "gsp_iterations.csv", dtype={"seed": str})
    chains = pd.read_csv(to / "gsp_chains.csv", dtype={"seed": str})
    iterations, chains = change(iterations, chains)
    iterations.to_csv(to / "gsp_iterations.csv", index=False)
    chains.to_csv(to / "gsp_chains.csv", index=False)
    return to


def test_rounding_of_another_cpu_passes(piloted: dict[str, Any], tmp_path: Path) -> None:
    """Every exported face and value a few ULPs off (another CPU's BLAS): still ok."""

    def nudge(it: pd.DataFrame, ch: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
        cols = [c for c in it.columns if c.startswith(("g_", "w_"))]
        cols += ["slider_value", "node_value", "value_before"]
        it[cols] = it[cols] * (1 + 4e-16) + 1e-16
        return it, ch

    reports = _replay_export(_tampered(piloted, tmp_path / "nudged", nudge))
    assert all(r["ok"] for r in reports), [r["mismatches"] for r in reports]
    assert max(r["weight_deviation"] for r in reports) > 0


def test_a_tampered_export_names_each_difference(piloted: dict[str, Any], tmp_path: Path) -> None:
    """One chosen value changed, one chain node dropped, one chain's initial face changed:
    each named by session, trial, chain, node and field, recorded vs rebuilt."""
    table = pd.read_csv(piloted["out"] / "gsp_iterations.csv")
    changed = table.iloc[5]
    sad = table[(table["emotion"] == "sad") & (table["chain"] == 1)]
    dropped = sad[sad["iteration"] == 1].iloc[0]  # not the chain's last node
    gene = json.loads(_gene_names(piloted["db"]))[2]

    def tamper(it: pd.DataFrame, ch: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
        it.loc[5, "slider_value"] = 0.123
        it = it.drop(index=dropped.name)
        first = (ch["emotion"] == "happy") & (ch["chain"] == 2)
        genes = json.loads(ch.loc[first, "initial_genes"].iloc[0])
        genes[2] += 0.25
        ch.loc[first, "initial_genes"] = json.dumps(genes)
        return it, ch

    reports = _replay_export(_tampered(piloted, tmp_path / "t", tamper))
    said = {r["session_id"]: r["mismatches"] for r in reports}
    at = (
        f"session {changed.session_id} trial {changed.trial + 1} "
        f"({changed.emotion} chain {changed.chain}, node {changed.iteration})"
    )
    assert (
        f"{at}: slider_value (position {changed.position}) recorded 0.123, rebuilt "
        f"{changed.slider_value:.12g}" in said[changed.session_id]
    ), said[changed.session_id]
    gone = f"session {dropped.session_id} trial {dropped.trial + 1}"
    assert (
        f"{gone}: answered (status done) but its answer is not in gsp_iterations"
        in (said[dropped.session_id])
    )
    after = sad[sad["iteration"] == 2].iloc[0]
    assert any(
        m.startswith(f"session {after.session_id} trial {after.trial + 1} (sad chain 1, node 2)")
        and "node 1 not in the export" in m
        for m in said[after.session_id]
    ), said[after.session_id]
    initial = [m for ms in said.values() for m in ms if m.startswith("happy chain 2: initial")]
    assert len(initial) == 1 and f"at {gene}: recorded" in initial[0], said
    chains = pd.read_csv(piloted["out"] / "gsp_chains.csv")
    maker = chains[(chains["emotion"] == "happy") & (chains["chain"] == 2)]["made_by_session_id"]
    touched = {changed.session_id, dropped.session_id, after.session_id, int(maker.iloc[0])}
    assert {r["session_id"] for r in reports if not r["ok"]} == touched  # nothing else


@pytest.mark.parametrize(
    ("block", "message"),
    [
        (
            {"slider": [0.6, 0.2]},
            r"slider must be \[lo, hi\] with 0 <= lo < hi <= 1; got \[0.6, 0.2\]",
        ),
        ({"chains": 1}, "one chain per concept and 3 iterations per participant"),
        ({"chain_scope": "within", "aggregation": 2}, "aggregation = 2 averages answers"),
        (
            {"aggregation": 2, "chains": 3, "iterations": 4},
            "after 3 answers they would wait for other participants",
        ),
        (
            {"dimensions": ["jawOpen", "jawOpen"]},
            r"dimensions must not repeat genes; got \['jawOpen'\]",
        ),
        ({"emotions": ["hapy"]}, r"\['hapy'\] not among the study's emotions"),
        ({"steps": 3}, "steps"),
    ],
)
def test_a_wrong_block_is_refused_by_name(block: dict[str, Any], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        study_from_dict({"name": "x", "emotions": ["happy"], "blocks": [{"task": "gsp", **block}]})


def test_wrong_answers_are_refused_and_leave_nothing(db_url: str, ict_model: Any) -> None:
    config = study_from_dict(
        {
            "name": "gsp-wrong",
            "emotions": ["happy"],
            "seed": 2,
            "correct": False,
            "blocks": [{"task": "gsp", "steps": 11, "iterations": 1}],
        }
    )
    store = Store(db_url)
    service = study_service(config, store, ict_model)
    try:
        token, _ = service.create_session("W")
        state = service.step(token, {"command": "begin", "key": new_key()})
        assert state["view"]["strip"] == [0, 1, 2, 4, 5, 6, 8, 9, 10]
        assert (
            len(state["view"]["frames"]) == 11
            and state["view"]["face"]["id"] == (state["view"]["slider"]["start"])
        )
        slide = {"command": "slide", "trial": 0}
        with pytest.raises(
            SelectionError, match="position must be an integer in \\[0, 10\\]; got 11"
        ):
            service.step(token, {**slide, "key": new_key(), "position": 11})
        with pytest.raises(SelectionError, match=r"strip's positions .* got 3"):
            service.step(token, {**slide, "key": new_key(), "position": 3, "fallback": True})
        with pytest.raises(
            ConfigError, match=r"position: Input should be a valid integer; got 2\.5"
        ):
            service.step(token, {**slide, "key": new_key(), "position": 2.5})
        with store.read() as db:
            from sqlalchemy import func, select

            from emogen.tasks.gsp.tables import GspIterationRow

            assert db.scalar(select(func.count()).select_from(GspIterationRow)) == 0
        done = service.step(token, {**slide, "key": new_key(), "position": 4, "fallback": True})
        assert done["stage"] == "done"
        with pytest.raises(StepConflict):
            service.step(token, {**slide, "key": new_key(), "position": 4})
        with store.read() as db:
            row = db.scalars(select(GspIterationRow)).one()
            assert row.fallback is True and row.slider_value == pytest.approx(0.4)
    finally:
        store.dispose()


def test_within_scope_chains_are_each_participants_own(db_url: str, ict_model: Any) -> None:
    config = study_from_dict(
        {
            "name": "gsp-own",
            "emotions": ["happy"],
            "seed": 2,
            "correct": False,
            "blocks": [
                {"task": "gsp", "steps": 11, "iterations": 4, "chains": 2, "chain_scope": "within"}
            ],
        }
    )
    store = Store(db_url)
    service = study_service(config, store, ict_model)
    try:
        for who in ("A", "B"):
            token, state = service.create_session(who)
            state = service.step(token, {"command": "begin", "key": new_key()})
            while state["stage"] != "done":
                body = {"command": "slide", "trial": state["progress"]["trial"], "position": 5}
                state = service.step(token, {**body, "key": new_key()})
        with store.read() as db:
            from sqlalchemy import text

            rows = db.execute(text("SELECT owner, chain, iterations FROM gsp_chains")).all()
        assert sorted(rows) == [(1, 0, 2), (1, 1, 2), (2, 0, 2), (2, 1, 2)]
    finally:
        store.dispose()


def test_aggregated_nodes_replay_from_an_export(tmp_path: Path, ict_dir: Path) -> None:
    """aggregation = 2: each node's value is the mean of two participants' answers; an export
    replays, and a changed first answer of a node is named with the node's value it breaks."""
    config = tmp_path / "agg.toml"
    config.write_text(
        STUDY.format(model=ict_dir).replace(
            "chains = 3\niterations = 4", "chains = 2\niterations = 2\naggregation = 2"
        )
    )
    url = f"sqlite:///{tmp_path / 'agg.sqlite'}"
    run = CliRunner().invoke
    args = ["study", "simulate", str(config), "-n", "4", "--seed", "1", "--database-url", url]
    assert run(app, args).exit_code == 0
    out = tmp_path / "export"
    args = ["study", "export", "--database-url", url, "--out", str(out), "--format", "csv"]
    assert run(app, args).exit_code == 0
    table = pd.read_csv(out / "gsp_iterations.csv")
    assert set(table["member"]) == {0, 1} and table["node_value"].notna().sum() == len(table) / 2
    assert all(r["ok"] for r in _replay_export(out))
    first = table[(table["member"] == 0) & (table["slider_value"] < 0.7)].iloc[0]
    table.loc[first.name, "slider_value"] += 0.1
    table.loc[first.name, "position"] += 1  # the answer itself changed: value and position
    table.to_csv(out / "gsp_iterations.csv", index=False)
    said = [m for r in _replay_export(out) for m in r["mismatches"]]
    node = (table["chain_id"] == first.chain_id) & (table["iteration"] == first.iteration)
    second = table[node & (table["member"] == 1)].iloc[0]
    at = f"session {second.session_id} trial {second.trial + 1} "
    assert any(m.startswith(at) and "node_value recorded" in m for m in said), said
