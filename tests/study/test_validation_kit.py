"""The validation kit of docs/appearance.md: examples/validate-stimuli.toml (a categorise block
over examples/prototypes.csv) runs with simulated raters, and every rater labels every row of
the stimulus file once — the row's intended emotion recorded beside the answer."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from typer.testing import CliRunner

from emogen.cli.app import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_validation_study_shows_every_stimulus_to_every_rater(
    tmp_path: Path, ict_dir: Path
) -> None:
    db = f"sqlite:///{tmp_path / 'v.db'}"
    config = str(EXAMPLES / "validate-stimuli.toml")
    result = CliRunner().invoke(
        app,
        [
            "study",
            "simulate",
            config,
            "--participants",
            "3",
            "--database-url",
            db,
            "--model",
            str(ict_dir),
        ],
    )
    assert result.exit_code == 0, result.output
    result = CliRunner().invoke(
        app, ["study", "export", "--database-url", db, "--out", str(tmp_path / "x")]
    )
    assert result.exit_code == 0, result.output
    stimuli = pd.read_csv(EXAMPLES / "prototypes.csv")
    responses = pd.read_parquet(tmp_path / "x" / "categorise_responses.parquet")
    assert responses.groupby("participant_id").size().tolist() == [len(stimuli)] * 3
    intended = responses.groupby("participant_id")["intended"].apply(sorted)
    for labels in intended:
        assert labels == sorted(stimuli["label"])
