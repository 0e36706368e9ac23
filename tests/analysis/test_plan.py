"""The multiplicity plan (emogen.analysis.plan): every test of a report found and marked primary
or exploratory, Holm over the primary family against statsmodels, a named primary test the data
could not support listed as not run, a bad --primary refused before any work; and the own-vs-
others effect size dz with its noncentral-t interval."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from typer.testing import CliRunner

from emogen.analysis.categorisation import dz_interval, own_advantage
from emogen.analysis.plan import check_primary, mark_roles, plan_table
from emogen.analysis.results import records_in, result_of
from emogen.cli.analysis import analysis_app
from emogen.errors import ConfigError

SUMMARY = {
    "source": "x",
    "categorisation": {
        "own_advantage": {"difference": 0.1, "ci_low": 0.0, "ci_high": 0.2, "p": 0.04, "dz": 0.5},
        "hit_rates": [
            {"emotion": "happy", "mean_difference": 0.3, "p": 0.001},
            {"emotion": "sad", "mean_difference": 0.1, "p": 0.03},
        ],
        "own_distance": {
            "primary": {"contrast": -1.0, "ci_low": -2.0, "ci_high": 0.1, "p": 0.02},
            "two_stage": {"mean_contrast": -0.5, "p_t": 0.2, "p_wilcoxon": 0.3},
        },
    },
    "conditions": {"emotion": {"p": 0.0002}},
}


def _results(summary: dict[str, object]):  # type: ignore[no-untyped-def]
    return [result_of(n, r) for n, r in records_in(summary)]


def test_every_test_is_found_and_marked() -> None:
    primary = ("categorisation.own_distance.primary", "categorisation.hit_rates")
    summary = {k: v for k, v in SUMMARY.items()}
    table = plan_table(mark_roles(_results(summary), primary))
    assert set(table["test"]) == {
        "categorisation.own_advantage",
        "categorisation.hit_rates[happy]",
        "categorisation.hit_rates[sad]",
        "categorisation.own_distance.primary",
        "categorisation.own_distance.two_stage",
        "conditions.emotion",
    }
    roles = dict(zip(table["test"], table["role"], strict=True))
    assert roles["categorisation.hit_rates[sad]"] == "primary"
    assert roles["conditions.emotion"] == "exploratory"
    assert list(table["role"][:3]) == ["primary"] * 3  # primary first
    assert summary["categorisation"]["own_advantage"]["role"] == "exploratory"  # in the JSON
    from statsmodels.stats.multitest import multipletests

    prim = table[table["role"] == "primary"]
    ref = multipletests(prim["p"].to_numpy(), method="holm")[1]
    assert prim["p_holm_primary"].to_numpy() == pytest.approx(ref)
    assert table.loc[table["role"] == "exploratory", "p_holm_primary"].isna().all()
    two = table.set_index("test").loc["categorisation.own_distance.two_stage"]
    assert two["p"] == 0.2 and two["estimate"] == -0.5


def test_a_bad_primary_name_is_refused_by_name() -> None:
    with pytest.raises(ConfigError, match="'own_distance'"):
        check_primary(("own_distance",))
    with pytest.raises(ConfigError, match="twice"):
        check_primary(("conditions.emotion", "conditions.emotion"))


def test_the_command_refuses_a_bad_primary_before_any_work(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        analysis_app,
        ["analyse", str(tmp_path), "--out", str(tmp_path / "o"), "--primary", "bogus"],
    )
    assert result.exit_code == 2 and "'bogus'" in result.output
    assert not (tmp_path / "o").exists()


def test_the_plan_in_the_json_has_no_nan(tmp_path: Path) -> None:
    import json

    from emogen.analysis.plan import plan_section

    primary = ("conditions.emotion",)
    plan = plan_section(mark_roles(_results(SUMMARY), primary), primary, tmp_path).data["plan"]
    text = json.dumps(plan)
    assert "NaN" not in text and plan["tests"][0]["p_holm_primary"] == 0.0002


def test_dz_interval_inverts_the_noncentral_t() -> None:
    rng = np.random.default_rng(2)
    diff = rng.normal(0.4, 1.0, size=15)
    t = float(stats.ttest_1samp(diff, 0.0).statistic)
    low, high = dz_interval(t, 15)
    assert stats.nct.cdf(t, 14, low * np.sqrt(15)) == pytest.approx(0.975, abs=1e-8)
    assert stats.nct.cdf(t, 14, high * np.sqrt(15)) == pytest.approx(0.025, abs=1e-8)
    assert low < diff.mean() / diff.std(ddof=1) < high


def test_own_advantage_reports_dz() -> None:
    import pandas as pd

    rows = []
    for i, (own, other) in enumerate([(1, 0), (1, 1), (1, 0), (0, 0), (1, 0), (1, 1)]):
        for source, hit in (("own", own), ("other", other)):
            rows.append(
                {
                    "participant_id": f"p{i}",
                    "source": source,
                    "fallback": False,
                    "intended": "happy",
                    "label": "happy" if hit else "sad",
                }
            )
    adv = own_advantage(pd.DataFrame(rows))
    diffs = np.array([1, 0, 1, 0, 1, 0], dtype=float)
    assert adv["dz"] == pytest.approx(diffs.mean() / diffs.std(ddof=1))


def test_dz_interval_past_scipys_noncentral_t_is_the_normal_approximation() -> None:
    low, high = dz_interval(-300.0, 50)  # nct.cdf is NaN this far out
    dz, half = -300.0 / np.sqrt(50), 1.959964 * np.sqrt(1 / 50 + (300.0**2 / 50) / 100)
    assert (low, high) == pytest.approx((dz - half, dz + half), rel=1e-6)
