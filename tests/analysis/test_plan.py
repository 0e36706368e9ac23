"""The multiplicity plan (emogen.analysis.plan): every test of a report found and marked primary
or exploratory, Holm over the primary family against statsmodels, a named primary test the data
could not support listed as not run, a bad --primary refused before any work; and the own-vs-
others effect size dz with its noncentral-t interval."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from typer.testing import CliRunner

from emogen.analysis.categorisation import dz_interval, own_advantage
from emogen.analysis.plan import check_primary, mark_roles, plan_table
from emogen.analysis.results import Result, Section, unregistered, write_analysis
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


def _results(summary: dict[str, Any]) -> list[Result]:
    """SUMMARY's tests as their sections register them (estimate, interval, p by hand)."""
    sec = Section(Path("."), data=summary)
    cat = summary["categorisation"]
    adv, od = cat["own_advantage"], cat["own_distance"]
    sec.add_test(
        "categorisation.own_advantage", adv, test="t", p=0.04, n=9, estimate=0.1,
        interval=(0.0, 0.2), effect=("dz", 0.5, None, None),
    )  # fmt: skip
    for row in cat["hit_rates"]:
        name = f"categorisation.hit_rates[{row['emotion']}]"
        sec.add_test(name, row, test="t", p=row["p"], n=9, estimate=row["mean_difference"])
    sec.add_test(
        "categorisation.own_distance.primary", od["primary"], test="permutation", p=0.02, n=9,
        estimate=-1.0, interval=(-2.0, 0.1),
    )  # fmt: skip
    sec.add_test(
        "categorisation.own_distance.two_stage", od["two_stage"], test="t", p=0.2, n=9,
        estimate=-0.5,
    )  # fmt: skip
    emotion = summary["conditions"]["emotion"]
    sec.add_test("conditions.emotion", emotion, test="permutation", p=0.0002, n=9)
    assert unregistered(sec) == []
    return sec.results


def test_every_test_is_found_and_marked() -> None:
    primary = ("categorisation.own_distance.primary", "categorisation.hit_rates")
    summary = copy.deepcopy(SUMMARY)
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


def test_a_test_not_run_is_listed_with_its_reason_and_left_out_of_holm(tmp_path: Path) -> None:
    """A study too small for one test: the test is in the plan as not run with its reason,
    not among the tests that ran, and Holm's family over the primary tests counts only those
    that ran (statsmodels on the two p-values)."""
    from statsmodels.stats.multitest import multipletests

    from emogen.analysis.plan import plan_section

    results = _results(copy.deepcopy(SUMMARY))
    small = Section(tmp_path)
    small.not_run("categorisation.fields_accuracy", "4 participants; the test needs 5", n=4)
    primary = ("categorisation.own_distance.primary", "conditions.emotion",
               "categorisation.fields_accuracy", "identity.distance")  # fmt: skip
    plan = plan_section(mark_roles(results + small.results, primary), primary, tmp_path)
    data = plan.data["plan"]
    ran = {t["test"]: t for t in data["tests"]}
    assert "categorisation.fields_accuracy" not in ran and len(ran) == len(results)
    assert data["not_run"] == [
        {"test": "categorisation.fields_accuracy", "role": "primary",
         "reason": "4 participants; the test needs 5"},
        {"test": "identity.distance", "role": "primary",
         "reason": "no section registered it (see its section)"},
    ]  # fmt: skip
    ref = multipletests([0.02, 0.0002], method="holm")[1]
    got = [ran[n]["p_holm_primary"] for n in primary[:2]]
    assert got == pytest.approx(ref)
    write_analysis("plan", tmp_path, [plan], {})
    table = pd.read_csv(tmp_path / "tables" / "plan_not_run.csv")
    assert list(table["test"]) == ["categorisation.fields_accuracy", "identity.distance"]
    assert "fields_accuracy" not in pd.read_csv(tmp_path / "tables" / "plan.csv")["test"].str.cat()
