"""``emogen replay --from-export`` of categorise blocks: what the export lets it rebuild from the
trials' seeds (the labels offered, the random faces drawn, each face's weights from its genes)
is checked and counted, a tampered value is named, and what it cannot rebuild (which other
participants' faces were drawn) is said with why — and the session is then not "ok"."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.cli.app import app

STUDY = """
name = "categorise-replay"
seed = 8
emotions = ["happy", "sad"]
correct = false
model = "{model}"

[[blocks]]
task = "gsp"
chains = 2
iterations = 2
steps = 11

[[blocks]]
task = "categorise"
random = 3
{others}
"""


def _pilot(root: Path, ict_dir: Path, others: str) -> Path:
    """Three simulated participants of the study, exported as CSV."""
    config = root / "study.toml"
    config.write_text(STUDY.format(model=ict_dir, others=others))
    url = f"sqlite:///{root / 'study.sqlite'}"
    run = CliRunner().invoke
    args = ["study", "simulate", str(config), "-n", "3", "--seed", "4", "--database-url", url]
    result = run(app, args)
    assert result.exit_code == 0, result.output
    out = root / "export"
    args = ["study", "export", "--database-url", url, "--out", str(out), "--format", "csv"]
    result = run(app, args)
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="module")
def random_faces(tmp_path_factory: pytest.TempPathFactory, ict_dir: Path) -> Path:
    return _pilot(tmp_path_factory.mktemp("random"), ict_dir, "")


@pytest.fixture(scope="module")
def others_faces(tmp_path_factory: pytest.TempPathFactory, ict_dir: Path) -> Path:
    return _pilot(tmp_path_factory.mktemp("others"), ict_dir, "others = 2")


def replay(folder: Path) -> list[dict[str, Any]]:
    result = CliRunner().invoke(app, ["replay", "--from-export", str(folder), "--json"])
    assert result.exit_code in (0, 1), result.output
    return list(json.loads(result.output))


def test_random_faces_and_label_orders_are_rebuilt_and_counted(random_faces: Path) -> None:
    reports = replay(random_faces)
    shown = pd.read_csv(random_faces / "categorise_responses.csv")
    per_session = shown.groupby("session_id").size().to_dict()  # counted by pandas
    assert set(shown["source"]) == {"random"}
    for r in reports:
        assert r["ok"] is True and r["unchecked"] == [] and r["mismatches"] == [], r
        n = per_session[r["session_id"]]
        assert r["checked"]["label orders"] == r["checked"]["faces re-drawn"] == n == 3
        assert r["checked"]["categorised faces"] == n


def test_a_tampered_categorise_export_names_each_difference(
    random_faces: Path, tmp_path: Path
) -> None:
    copy = tmp_path / "t"
    shutil.copytree(random_faces, copy)
    shown = pd.read_csv(copy / "categorise_responses.csv", dtype={"seed": str})
    gene = next(c for c in shown.columns if c.startswith("g_"))
    shown.loc[0, gene] = shown.loc[0, gene] + 0.5  # a face's gene: not what the seed drew
    labels = shown.loc[1, "labels"].split("|")
    shown.loc[1, "labels"] = "|".join(reversed(labels))  # the order offered
    shown.loc[2, "source_label"] = "made-up"
    shown.to_csv(copy / "categorise_responses.csv", index=False)
    said = {r["session_id"]: r["mismatches"] for r in replay(copy)}
    first = [f"session {shown.session_id[i]} trial {shown.trial[i] + 1}" for i in range(3)]
    mine = said[int(shown.session_id[0])]
    assert any(
        m.startswith(first[0]) and "g_ columns (the face drawn)" in m and gene[2:] in m
        for m in mine
    ), mine
    assert any(m.startswith(first[0]) and "its weights from its genes" in m for m in mine)
    expected = (
        f"{first[1]} (random face): labels recorded {list(reversed(labels))}, the trial's "
        f"seed gives {labels}"
    )
    assert expected in said[int(shown.session_id[1])]
    assert any(
        m.startswith(first[2]) and "source_label recorded made-up" in m
        for m in said[int(shown.session_id[2])]
    )


def test_others_faces_are_said_not_checked_and_why(others_faces: Path) -> None:
    reports = replay(others_faces)
    shown = pd.read_csv(others_faces / "categorise_responses.csv")
    for r in reports:
        mine = shown[shown["session_id"] == r["session_id"]]
        others = sorted(mine.loc[mine["source"] == "other", "trial"] + 1)
        random = mine[mine["source"] == "random"]
        assert r["ok"] is False and r["mismatches"] == [], r
        assert len(others) == 2 and r["checked"]["label orders"] == len(mine)
        said = " ".join(r["unchecked"])
        joined = "–" if others[1] == others[0] + 1 else ", "
        assert f"trials {others[0]}{joined}{others[1]} (2 other faces)" in said
        assert "sessions completed when the block started" in said
        # the random faces were drawn after the others': not re-drawn either, and said so
        assert f"({len(random)} random faces)" in said and "after others' faces" in said
        assert "faces re-drawn" not in r["checked"]
    result = CliRunner().invoke(app, ["replay", "--from-export", str(others_faces)])
    assert result.exit_code == 1
    assert "NOT ALL CHECKED" in result.output and "every face matches" not in result.output
