"""The analysis commands through their Typer app: power, replicate (one section; the whole
quick run is marked slow)."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from emogen.cli.analysis import analysis_app

runner = CliRunner()


def test_power_command(ict_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "power"
    result = runner.invoke(
        analysis_app,
        [
            "power",
            "--out",
            str(out),
            "--model",
            str(ict_dir),
            "--a",
            "mouthSmile=0.9",
            "--a",
            "cheekSquint=0.6",
            "--difference",
            "browInnerUp=0.8",
            "--generations",
            "3",
            "--replicates",
            "40",
            "--permutations",
            "40",
            "--max-participants",
            "12",
        ],
    )
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "power.json").read_text())
    assert summary["n_required"] is not None and 4 <= summary["n_required"] <= 12
    lo, hi = summary["n_required_ci95"]  # the upper end may lie beyond the simulated n
    assert lo <= summary["n_required"] and (hi is None or summary["n_required"] <= hi)
    assert summary["n_required_method"] in ("fit", "interpolation")
    assert summary["prototype_cd"] > 0.15
    curve = pd.read_csv(out / "power.csv")
    assert list(curve.columns) == ["n", "power", "se", "fitted", "false_positive", "fp_se"]
    assert (out / "power.png").is_file()
    assert "participants per group reach power 0.8" in result.output
    # spread and choice noise left out: both flagged as assumptions, in the output and the JSON
    assert result.output.count("ASSUMPTION") >= 2 and len(summary["assumptions"]) == 2
    assert "false positives" in result.output and summary["max_false_positive"] <= 0.2


def test_power_command_refuses_a_difference_cd_cannot_see(ict_dir: Path, tmp_path: Path) -> None:
    base = [
        "power",
        "--out",
        str(tmp_path),
        "--model",
        str(ict_dir),
        "--a",
        "mouthSmile=0.4",
        "--b",
        "mouthSmile=0.8",
        "--participant-sd",
        "0",
        "--noise-temperature",
        "0",
    ]
    result = runner.invoke(analysis_app, base)
    assert result.exit_code == 2 and "only in intensity" in result.output
    assert "--statistic cd" in result.output and "--observer cd" in result.output


def test_power_command_needs_one_group_b(ict_dir: Path, tmp_path: Path) -> None:
    result = runner.invoke(
        analysis_app, ["power", "--out", str(tmp_path), "--model", str(ict_dir), "--a", "jawOpen=1"]
    )
    assert result.exit_code == 2 and "--b or --difference" in result.output


def test_analyse_command_reports_a_bad_folder(ict_dir: Path, tmp_path: Path) -> None:
    result = runner.invoke(
        analysis_app,
        ["analyse", str(tmp_path), "--out", str(tmp_path / "o"), "--model", str(ict_dir)],
    )
    assert result.exit_code == 2 and "neither a study export" in result.output


def _section(ict_dir: Path, out: Path, words: str, runs: int) -> tuple[pd.DataFrame, str]:
    """``emogen replicate --quick --only WORDS --no-render --runs RUNS``: (findings, output)."""
    result = runner.invoke(
        analysis_app,
        [
            "replicate",
            "--quick",
            "--out",
            str(out),
            "--model",
            str(ict_dir),
            "--only",
            words,
            "--no-render",
            "--runs",
            str(runs),
        ],
    )
    assert result.exit_code == 0, result.output
    return pd.read_csv(out / "tables" / "findings.csv"), result.output


def test_replicate_one_section(ict_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "rep"
    findings, output = _section(ict_dir, out, "activation", 40)
    assert len(findings) == 5 and set(findings["section"]) == {"Table IV"}
    verdicts = findings["verdict"]  # the machine table: plain values, one per cell
    assert verdicts.isin(["holds", "partly", "differs", "inconclusive"]).all()
    # every verdict from three seeds, by a written rule: on the pooled runs' interval where
    # the finding has one, else inconclusive exactly when the seeds disagree
    assert (findings["n_seeds"] == 3).all()
    per_seed = findings[["verdict_seed_1", "verdict_seed_2", "verdict_seed_3"]].apply(list, axis=1)
    from emogen.analysis.replication.verdicts import RULES

    assert findings["rule"].str.extract(r"^(\w+)")[0].isin(list(RULES)).all()
    agree = per_seed.map(lambda v: len(set(v)) == 1)
    pooled = findings["pooled_interval"].notna()
    assert ((verdicts == "inconclusive") == ~agree)[~pooled].all()
    compromise = findings[findings["paper_finding"].str.startswith("3–8")].iloc[0]
    assert pooled.all() and "paired t, n = 120" in compromise["pooled_interval"]
    sigma0 = findings[findings["paper"].str.startswith("0.370")].iloc[0]
    assert "paired bootstrap of the SD difference, n = 120" in sigma0["pooled_interval"]
    assert "Table IV" in output and "paper findings:" in output
    readme = (out / "README.md").read_text()
    assert "9,592" in readme
    # --quick has its own seeds (not a prefix of the full run's seed 1); the run is recorded
    assert "seeds: `101, 102, 103`" in readme and "model hash: `" in readme
    assert "git commit: `" in readme and "command: `emogen replicate --quick --runs 40" in readme


def test_replicate_table_iii_reads_both_ways(ict_dir: Path, tmp_path: Path) -> None:
    findings, _ = _section(ict_dir, tmp_path / "rep3", "repeatability", 30)
    assert set(findings["section"]) == {"Table III"}
    slope = findings[findings["paper_finding"].str.startswith("protocol repeatability")].iloc[0]
    # two matched-bias parts in first-bin points, two within-initialisation slopes
    assert slope["pooled_interval"].count("first-bin points, n = 90") == 2
    assert slope["pooled_interval"].count("points per unit bias, n = 90") == 2
    assert "matched bias" in slope["ours_first_seed"] and "readings" in slope["rule"]
    bias = findings[findings["paper_finding"].str.startswith("protocol initialisation")].iloc[0]
    assert bias["pooled_interval"].count("paired t, n = 90") == 2


@pytest.mark.slow
def test_replicate_quick(ict_dir: Path, tmp_path: Path) -> None:
    """The CI run of the whole quick replication (about a minute on two cores)."""
    out = tmp_path / "quick"
    result = runner.invoke(
        analysis_app, ["replicate", "--quick", "--out", str(out), "--model", str(ict_dir)]
    )
    assert result.exit_code == 0, result.output
    findings = pd.read_csv(out / "tables" / "findings.csv")
    assert len(findings) >= 30
    sections = set(findings["section"])
    for s in (
        "Table I",
        "Table III",
        "Table IV",
        "Table V",
        "Fig. 11",
        "Fig. 14",
        "Selection pressure",
    ):
        assert s in sections, s
    verdicts = findings["verdict"]
    assert verdicts.isin(["holds", "partly", "differs", "inconclusive"]).all()
    # our own checks (GA-noise test, correctives) are reported apart, outside the tally
    ours = pd.read_csv(out / "tables" / "our_checks.csv")
    assert set(ours["section"]) == {"GA noise (Section IV-C)", "Section III-A"}
    assert "GA noise (Section IV-C)" not in sections
    html = (out / "index.html").read_text()
    assert "9,592" in html and "simulated participants" in html
    for fig in ("fig8_cd", "fig9_mean_faces", "fig15_kl_default", "table_iii_bins", "power"):
        assert (out / "figures" / f"{fig}.png").is_file(), fig


def test_replicate_seeds_default_ten_quick_three() -> None:
    """Verdicts decided at the seed level need ten seeds by default (docs/replication uses
    10); ``--quick`` stays a three-seed smoke run; an explicit ``--seeds`` wins over both."""
    from emogen.analysis.replication import ReplicateSettings

    assert ReplicateSettings.full_settings().seeds == 10
    assert ReplicateSettings.quick_settings().seeds == 3
    assert ReplicateSettings.quick_settings(seeds=5).seeds == 5
    result = runner.invoke(analysis_app, ["replicate", "--help"], env={"COLUMNS": "250"})
    assert "default 10" in result.output and "--quick: 3" in result.output
    bad = runner.invoke(analysis_app, ["replicate", "--out", "x", "--seeds", "0"])
    assert bad.exit_code == 2 and "--seeds" in bad.output
