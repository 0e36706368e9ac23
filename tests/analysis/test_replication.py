"""The replication package's parts: findings, statistics, the condition runner, a section's
typed result."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.replication import ConditionRunner, ConditionSpec, Finding, ReplicateSettings
from emogen.analysis.replication.findings import cohen_d, graded, pm
from emogen.analysis.replication.ga_settings import selection_pressure


def test_finding_rejects_an_unknown_verdict() -> None:
    with pytest.raises(ValueError, match="verdict"):
        Finding("x", "claim", "1", "2", "maybe")
    assert Finding("Fig. 1", "c", "p", "o", "holds").line().startswith("[ holds ] Fig. 1")


def test_cohen_d_against_a_plain_formula() -> None:
    rng = np.random.default_rng(0)
    a, b = rng.normal(1.0, 1.0, 30), rng.normal(0.0, 2.0, 50)
    pooled = np.sqrt((29 * np.var(a, ddof=1) + 49 * np.var(b, ddof=1)) / 78)
    assert cohen_d(a, b) == pytest.approx((a.mean() - b.mean()) / pooled)
    assert cohen_d(np.ones(3), np.ones(4)) == 0.0


def test_small_helpers() -> None:
    assert pm(0.5, 0.25) == "0.500 ± 0.250"
    assert pm(None, None) == "–"
    assert [graded(True, True), graded(False, True), graded(False, False)] == [
        "holds",
        "partly",
        "differs",
    ]


def test_conditions_are_simulated_once_and_by_their_settings(ict_model) -> None:  # type: ignore[no-untyped-def]
    runner = ConditionRunner(ict_model, ReplicateSettings(runs=8))
    a = runner.condition("a", {"jawOpen": 1.0})
    assert runner.condition("again", {"jawOpen": 1.0}, ConditionSpec()) is a
    c = runner.condition("c", {"jawOpen": 1.0}, ConditionSpec(variant="classical"))
    assert c is not a and a.errors.shape == (8, 11) and a.final.shape[0] == 8
    np.testing.assert_array_equal(a.final_errors, a.errors[:, -1])


def test_selection_pressure_returns_its_table_and_finding(ict_model) -> None:  # type: ignore[no-untyped-def]
    runner = ConditionRunner(ict_model, ReplicateSettings(runs=12))
    res = selection_pressure(runner)
    assert list(res.table["target"]) == ["target 1", "target 3", "target 2"]
    assert res.table["Cohen's d"].tolist() == pytest.approx(list(res.cohen_d.values()))
    # "no difference" needs an equivalence test: 12 runs per target are too few to show it
    (found,) = res.findings
    assert len(found.evidence) == 3 and "TOST" in found.interval
    assert found.verdict == "inconclusive"
