"""The `emogen` command line, run as a user would."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from typer.testing import CliRunner

from emogen.cli import app

runner = CliRunner()


def test_model_info_json_reports_the_whole_model(ict_dir: Path, ict_model) -> None:
    # the real console entry point, in a fresh process
    proc = subprocess.run(
        [sys.executable, "-m", "emogen", "model", "info", str(ict_dir), "--json"],
        capture_output=True,
        text=True,
        check=True,
    )
    info = json.loads(proc.stdout)
    assert info["n_vertices"] == 26719
    assert set(info["shapes"]) == set(ict_model.shape_names) and len(info["shapes"]) == 57
    genes = [g["name"] for g in info["rig"]["genes"]]
    assert "mouthSmile" in genes and len(genes) == 30
    assert info["rig"]["emotions"]["happy"]["core"] == [
        "cheekSquint",
        "mouthSmile",
        "mouthLowerDown",
    ]
    assert {"face", "teeth", "tooth_upper_left_incisor_central"} <= set(info["regions"])
    assert info["model_hash"] == ict_model.model_hash


def test_model_info_text(ict_dir: Path) -> None:
    result = runner.invoke(app, ["model", "info", str(ict_dir)])
    assert result.exit_code == 0, result.output
    assert "26719 vertices" in result.output and "eyeLookLeft" in result.output


def test_no_model_anywhere_says_how_to_get_one(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("EMOGEN_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("EMOGEN_MODEL", raising=False)
    result = runner.invoke(app, ["model", "info"])
    assert result.exit_code == 4  # an environment error (docs/cli.md)
    assert "emogen model fetch" in result.output and "EMOGEN_MODEL" in result.output


def test_env_var_is_used_and_checked(ict_dir: Path, monkeypatch, tmp_path: Path) -> None:
    monkeypatch.setenv("EMOGEN_MODEL", str(ict_dir))
    assert runner.invoke(app, ["model", "info", "--json"]).exit_code == 0
    monkeypatch.setenv("EMOGEN_MODEL", str(tmp_path / "gone"))
    result = runner.invoke(app, ["model", "info"])
    assert result.exit_code == 4 and "EMOGEN_MODEL points at" in result.output


def test_bad_weight_option_is_named(ict_dir: Path, tmp_path: Path) -> None:
    result = runner.invoke(
        app,
        [
            "model",
            "export",
            "--face",
            "--model",
            str(ict_dir),
            "--weight",
            "jawOpen:1",
            "--out",
            str(tmp_path / "a.obj"),
        ],
    )
    assert result.exit_code == 2 and "NAME=VALUE; got 'jawOpen:1'" in result.output
