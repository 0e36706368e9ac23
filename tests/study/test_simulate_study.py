"""``emogen study simulate``: simulated participants through the real service, known answers.

The known answer: participants label faces near their own prototypes (their own faces) more
accurately than faces near others' (others' faces); with the prototypes shuffled between
participants (each labels with somebody else's), the advantage vanishes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.analysis.categorisation import accuracy_by_source, own_advantage
from emogen.cli.app import app
from emogen.errors import ConfigError
from emogen.study.config import study_from_dict
from emogen.study.export import export_tables
from emogen.study.simulate import SimulationPlan, simulate_study
from emogen.study.storage import Store
from emogen.tasks.simulated import SimulatedDesign

PILOT: dict[str, Any] = {
    "name": "pilot",
    "seed": 3,
    "emotions": ["happy", "sad", "angry", "fearful"],
    "identities": ["generic"],
    "ga": {"generations": 6, "min_selections": 1, "max_selections": 5},
    "blocks": [
        {"task": "evolve"},
        {"task": "categorise", "own": True, "others": 8, "random": 2, "intensity": True},
    ],
}


#: The default design, stated: individual differences of SD 0.5 in an emotion's genes.
DESIGN = SimulatedDesign(spread=0.5, label_noise=0.15)


def run(tmp_path: Path, model: Any, name: str, n: int = 24, **plan: Any) -> dict[str, pd.DataFrame]:
    url = f"sqlite:///{tmp_path / f'{name}.sqlite'}"
    cfg = study_from_dict(PILOT)
    simulate_study(
        SimulationPlan(
            cfg,
            url,
            seed=plan.pop("seed", 11),
            participants=n,
            design=DESIGN,
            shuffle_prototypes=plan.pop("shuffle", False),
        ),
        model=model,
        **plan,
    )
    store = Store(url)
    try:
        return export_tables(store)
    finally:
        store.dispose()


def test_own_faces_are_labelled_better_and_not_with_shuffled_prototypes(
    tmp_path: Path, ict_model: Any
) -> None:
    tables = run(tmp_path, ict_model, "known")
    for name in (
        "sessions",
        "trials",
        "faces",
        "selections",
        "evolve_ratings",
        "categorise_responses",
    ):
        assert set(tables[name]["participant_source"]) == {"simulated"}, name
    assert (tables["sessions"]["stage"] == "done").all()
    effect = own_advantage(tables["categorise_responses"])
    assert effect["n_participants"] == 23  # the first participant has no others' faces yet
    assert effect["ci_low"] > 0, effect
    null = own_advantage(run(tmp_path, ict_model, "shuffled", shuffle=True)["categorise_responses"])
    assert null["ci_low"] < 0 < null["ci_high"], null
    assert abs(null["difference"]) < effect["difference"]


def test_the_same_seed_gives_the_same_data(tmp_path: Path, ict_model: Any) -> None:
    a = run(tmp_path, ict_model, "a", n=3)
    b = run(tmp_path, ict_model, "b", n=3)
    for name in ("faces", "categorise_responses", "selections", "evolve_ratings"):
        keep = [c for c in a[name].columns if not c.endswith(("_at", "_ms"))]
        pd.testing.assert_frame_equal(a[name][keep], b[name][keep], check_like=False)
    c = run(tmp_path, ict_model, "c", n=3, seed=12)
    assert not np.array_equal(
        a["categorise_responses"]["w_jawOpen"], c["categorise_responses"]["w_jawOpen"]
    )


def test_two_workers_run_every_participant(tmp_path: Path, ict_model: Any) -> None:
    tables = run(tmp_path, ict_model, "workers", n=4, workers=2)
    assert sorted(tables["sessions"]["participant_id"]) == [f"sim-{k:04d}" for k in range(1, 5)]
    assert (tables["sessions"]["stage"] == "done").all()


def test_a_database_with_sessions_and_wrong_options_are_refused(
    tmp_path: Path, ict_model: Any
) -> None:
    run(tmp_path, ict_model, "used", n=1)
    with pytest.raises(ConfigError, match="already holds 1 session"):
        run(tmp_path, ict_model, "used", n=1)
    with pytest.raises(ConfigError, match="--participants must be >= 1; got 0"):
        run(tmp_path, ict_model, "zero", n=0)
    with pytest.raises(ConfigError, match="label_noise must be a finite number >= 0; got -1"):
        SimulatedDesign(label_noise=-1)
    result = CliRunner().invoke(app, ["study", "simulate", str(tmp_path / "nope.toml")])
    assert result.exit_code != 0 and "nope.toml does not exist" in result.output


def test_own_advantage_matches_a_plain_computation() -> None:
    rows = []
    hits = {
        "p1": ([1, 1, 0, 1], [0, 1, 0, 0]),
        "p2": ([1, 1, 1, 1], [1, 0, 1, 1]),
        "p3": ([0, 1, 1, 1], [1, 1, 0, 0]),
    }
    for pid, (own, other) in hits.items():
        for source, seq in (("own", own), ("other", other)):
            for hit in seq:
                rows.append(
                    {
                        "participant_id": pid,
                        "source": source,
                        "fallback": False,
                        "intended": "happy",
                        "label": "happy" if hit else "sad",
                    }
                )
    rows.append(
        {
            "participant_id": "p1",
            "source": "other",
            "fallback": True,
            "intended": "sad",
            "label": "sad",
        }
    )  # a fallback: left out
    table = pd.DataFrame(rows)
    per = accuracy_by_source(table).set_index("participant_id")
    assert per.loc["p1", "accuracy_other"] == 0.25 and per.loc["p1", "n_other"] == 4
    diffs = [np.mean(o) - np.mean(t) for o, t in hits.values()]
    mean, sd = np.mean(diffs), np.std(diffs, ddof=1)
    half = 4.302652729911275 * sd / np.sqrt(3)  # t(0.975, df=2)
    got = own_advantage(table)
    assert got["difference"] == pytest.approx(mean)
    assert (got["ci_low"], got["ci_high"]) == pytest.approx((mean - half, mean + half))


def test_emogen_analyse_reads_a_study_of_evolve_and_categorise_blocks(
    tmp_path: Path, ict_model: Any, ict_dir: Path
) -> None:
    """The GA analysis takes the evolve trials (categorise trials have no emotion of their own:
    they once stopped it, "column 'emotion' row 9: empty") and the report has the
    categorisation, with the participant as the unit."""
    import json

    from emogen.study.export import write_export

    tables = run(tmp_path, ict_model, "analysed", n=6)
    write_export(tables, tmp_path / "export")
    out = tmp_path / "analysis"
    result = CliRunner().invoke(
        app,
        [
            "analyse",
            str(tmp_path / "export"),
            "--out",
            str(out),
            "--model",
            str(ict_dir),
            "--noise-runs",
            "20",
            "--no-render",
        ],
    )
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "analysis.json").read_text())
    assert set(summary["groups"]) == {"happy", "sad", "angry", "fearful"}
    reported = summary["categorisation"]["own_advantage"]
    expected = own_advantage(tables["categorise_responses"])
    assert reported["n_participants"] == expected["n_participants"] == 5
    assert reported["difference"] == pytest.approx(expected["difference"])
    assert (
        summary["categorisation"]["n_answers"]
        == tables["categorise_responses"]["label"].notna().sum()
    )
    html = (out / "index.html").read_text()
    assert "Categorisation of faces" in html and "the participant is the unit" in html
    per = pd.read_csv(out / "tables" / "categorisation_participants.csv")
    assert len(per) == 6
