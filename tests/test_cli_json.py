"""`--json`: one JSON object on stdout and nothing else there; and the output paths a command
must refuse (a JPEG name for a PNG, an existing file where a folder goes) write nothing."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.cli import app
from emogen.cli.options import stage_printer

runner = CliRunner()  # click 8.2: .stdout and .stderr apart, .output both


def _json(args: list[str]) -> dict:  # type: ignore[type-arg]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, (result.stdout, result.stderr)
    return json.loads(result.stdout)  # the whole of stdout is one JSON object


def test_simulate_json_is_the_whole_of_stdout_and_matches_the_files(
    ict_dir: Path, tmp_path: Path
) -> None:
    out = tmp_path / "sim"
    args = ["simulate", "-t", "jawOpen=0.8", "--runs", "3", "--generations", "2", "--seed", "5"]
    data = _json([*args, "--out", str(out), "--model", str(ict_dir), "--json"])
    table = pd.read_csv(out / "simulation.csv")
    last = table[table["generation"] == 2]["elite_error"]
    assert data["runs"] == 3 and data["seed"] == 5 and data["metric"] == "cd"
    assert data["elite_error"][-1]["generation"] == 2
    assert data["elite_error"][-1]["mean"] == pytest.approx(last.mean())
    assert {Path(p).name for p in data["wrote"]} >= {"simulation.csv", "simulation.json"}
    assert all(Path(p).parent == out for p in data["wrote"])  # the final folder, not a temporary


def test_correct_and_model_export_json(ict_dir: Path, tmp_path: Path) -> None:
    src = tmp_path / "faces.csv"
    src.write_text("jawOpen,mouthSmile\n0.5,0.2\n1,0\n")
    data = _json(
        ["correct", str(src), "--out", str(tmp_path / "c.csv"), "--model", str(ict_dir), "--json"]
    )
    assert data["faces"] == 2 and data["wrote"] == [str(tmp_path / "c.csv")]
    obj = tmp_path / "face.obj"
    data = _json(
        [
            "model",
            "export",
            "--face",
            "-w",
            "jawOpen=1",
            "--out",
            str(obj),
            "--model",
            str(ict_dir),
            "--json",
        ]
    )
    assert data == {"wrote": str(obj)} and obj.stat().st_size > 0


def test_render_json_and_a_jpeg_name_is_refused(ict_dir: Path, tmp_path: Path) -> None:
    png = tmp_path / "a.png"
    data = _json(
        [
            "render",
            "-w",
            "jawOpen=1",
            "--size",
            "64",
            "--out",
            str(png),
            "--model",
            str(ict_dir),
            "--json",
        ]
    )
    assert data["wrote"] == [str(png)] and png.read_bytes()[:4] == b"\x89PNG"
    for args in (["render"], ["render", "sheet", "--face", "neutral"], ["render", "heatmap"]):
        jpg = tmp_path / "b.jpg"
        result = runner.invoke(app, [*args, "--out", str(jpg), "--model", str(ict_dir)])
        assert result.exit_code == 2, (args, result.stderr)
        assert f"--out {jpg}: EmoGen writes PNG images" in result.stderr
        assert not jpg.exists()  # neither a file nor a folder


def test_an_existing_file_as_out_folder_is_a_usage_error(ict_dir: Path, tmp_path: Path) -> None:
    afile = tmp_path / "results"
    afile.write_text("my notes")
    result = runner.invoke(
        app,
        [
            "simulate",
            "-t",
            "jawOpen=1",
            "--runs",
            "2",
            "--out",
            str(afile),
            "--model",
            str(ict_dir),
        ],
    )
    assert result.exit_code == 2 and f"--out {afile} is a file" in result.stderr
    assert afile.read_text() == "my notes" and sorted(tmp_path.iterdir()) == [afile]


def test_progress_goes_to_stderr_only_when_asked_or_on_a_terminal(capsys) -> None:  # type: ignore[no-untyped-def]
    assert stage_printer(False) is None
    assert stage_printer(None) is None  # pytest's stderr is not a terminal
    show = stage_printer(True)
    assert show is not None
    show("separability")
    captured = capsys.readouterr()
    assert captured.out == "" and "] separability" in captured.err


def test_power_json_matches_its_files_and_keeps_assumptions_on_stderr(
    ict_dir: Path, tmp_path: Path
) -> None:
    out = tmp_path / "power"
    result = runner.invoke(
        app,
        [
            "power",
            "--out",
            str(out),
            "--model",
            str(ict_dir),
            "--a",
            "mouthSmile=0.9",
            "--difference",
            "browInnerUp=0.8",
            "--generations",
            "2",
            "--replicates",
            "20",
            "--permutations",
            "20",
            "--max-participants",
            "6",
            "--json",
        ],
    )
    assert result.exit_code == 0, (result.stdout, result.stderr)
    data = json.loads(result.stdout)  # the whole of stdout
    on_disk = json.loads((out / "power.json").read_text())
    curve = pd.read_csv(out / "power.csv")
    assert data["n_required"] == on_disk["n_required"]
    assert [r["n"] for r in data["curve"]] == curve["n"].tolist()
    assert [r["false_positive"] for r in data["curve"]] == pytest.approx(
        curve["false_positive"].tolist()
    )
    assert len(data["assumptions"]) == 2 and result.stderr.count("ASSUMPTION") == 2
    assert all(Path(p).parent == out for p in data["wrote"])
