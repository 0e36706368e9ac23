"""The verdict rules and their combination over seeds, against plain formulas."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from emogen.analysis.replication.findings import Finding, mean_diff_ci
from emogen.analysis.replication.verdicts import (
    RULES,
    ci_verdict,
    combine,
    join,
    mean_ci,
    number_verdict,
)


def f(verdict: str, value: float | None = None, claim: str = "c") -> Finding:
    return Finding("S", claim, "p", "o", verdict, rule="order: x", value=value, value_label="v")


def test_ci_rule() -> None:
    assert ci_verdict(0.01, 0.2, +1, 0.05) == "holds"
    assert ci_verdict(-0.2, -0.01, +1, 0.05) == "differs"
    assert ci_verdict(-0.2, -0.01, -1, 0.05) == "holds"
    assert ci_verdict(-0.1, 0.1, +1, 0.05) == "inconclusive"


def test_ci_rule_fails_a_precisely_zero_effect() -> None:
    """A precise zero — and a precise effect smaller than the smallest of interest, on
    either side — is no effect of interest: the claim of a difference fails."""
    assert ci_verdict(-0.001, 0.001, +1, 0.05) == "differs"
    assert ci_verdict(0.01, 0.04, +1, 0.05) == "differs"
    assert ci_verdict(-0.04, -0.01, -1, 0.05) == "differs"
    with pytest.raises(ValueError, match="smallest effect of interest must be > 0; got 0"):
        ci_verdict(0.1, 0.2, +1, 0)


def test_number_rule_judges_the_table_v_threshold_as_different() -> None:
    """Ours 0.106 (95% CI 0.100…0.112) ± 0.044 against the paper's 0.2 ± 0.065: the nearest
    end of the CI is 0.088 / 0.0555 = 1.6 pooled σ away."""
    pooled = np.sqrt((0.044**2 + 0.065**2) / 2)
    assert 0.088 / pooled > 1
    assert number_verdict(0.100, 0.112, 0.044, 0.2, 0.065) == "differs"
    assert number_verdict(0.20, 0.21, 0.06, 0.2, 0.065) == "holds"
    assert number_verdict(0.24, 0.25, 0.06, 0.2, 0.065) == "partly"


def test_parts() -> None:
    assert join(["holds", "holds"]) == "holds"
    assert join(["holds", "inconclusive"]) == "inconclusive"
    assert join(["differs", "inconclusive"]) == "inconclusive"
    assert join(["holds", "differs"]) == "partly"
    assert join(["inconclusive", "inconclusive"]) == "inconclusive"


def test_mean_ci_is_the_t_interval() -> None:
    v = [0.2, 0.25, 0.31]
    mean, half = mean_ci(v)
    lo, hi = stats.t.interval(0.95, 2, loc=np.mean(v), scale=stats.sem(v))
    assert mean == pytest.approx(np.mean(v)) and half == pytest.approx((hi - lo) / 2)
    assert np.isnan(mean_ci([0.3])[1])


def test_mean_diff_ci_is_welch_normal() -> None:
    rng = np.random.default_rng(0)
    a, b = rng.normal(1, 1, 200), rng.normal(0.8, 2, 300)
    d, lo, hi = mean_diff_ci(a, b)
    se = np.sqrt(a.var(ddof=1) / 200 + b.var(ddof=1) / 300)
    assert d == pytest.approx(a.mean() - b.mean()) and hi - lo == pytest.approx(2 * 1.96 * se)


def test_seeds_that_disagree_make_a_finding_inconclusive() -> None:
    seeds = [
        [f("holds", 0.3, "a"), f("holds", 1.0, "b"), f("partly", None, "mine")],
        [f("holds", 0.2, "a"), f("differs", -1.0, "b")],
        [f("holds", 0.25, "a"), f("holds", 2.0, "b")],
    ]
    a, b, mine = combine(seeds)
    assert (a.verdict, a.seed_verdicts) == ("holds", ("holds",) * 3)
    assert b.verdict == "inconclusive" and b.seed_verdicts == ("holds", "differs", "holds")
    assert a.mean == pytest.approx(0.25) and "±" in a.effect
    assert mine.verdict == "partly" and mine.effect == "–"  # one seed, no value
    assert a.as_finding().verdict == "holds"


def test_every_rule_a_finding_names_is_written_down() -> None:
    assert set(RULES) >= {"order", "ci", "number", "direction", "threshold", "kl"}
    assert set(RULES) >= {"tost", "noninferior", "level", "compromise"}


def test_tally_both_ways_counts_like_a_plain_loop() -> None:
    from emogen.analysis.replication.write_report import tally_both_ways

    verdicts = ["holds"] * 4 + ["partly"] * 3 + ["differs"] * 2 + ["inconclusive"] * 5
    counts = {v: 0 for v in ("holds", "partly", "differs", "inconclusive")}
    for v in verdicts:
        counts[v] += 1
    text = tally_both_ways(verdicts)
    assert text.startswith("4 hold, 3 partly, 2 differ, 5 inconclusive")
    assert "strictly 4 of 14 hold" in text and "leniently (partly counted) 7 of 14" in text
    assert "among the 9 decided, 4 hold and 7 hold at least partly, 2 differ" in text


def test_the_change_table_lists_moved_verdicts_and_findings_that_left_the_tally() -> None:
    """Against the previous report's verdicts: a changed verdict is listed with the rule
    changes that apply to it; an unchanged one is not, unless it left the tally."""
    from emogen.analysis.replication.previous import BEFORE
    from emogen.analysis.replication.settings import ReplicateSettings
    from emogen.analysis.replication.verdicts import Combined
    from emogen.analysis.replication.write_report import _changed

    (s1, c1), (n1, v1) = next(iter(BEFORE.items()))
    (s2, c2), (_, v2) = list(BEFORE.items())[1]
    (s3, c3), (n3, v3) = list(BEFORE.items())[2]
    other = next(v for v in ("holds", "differs") if v != v1)
    moved = Finding(s1, c1, "p", "o", other, fitted="GMM")
    same = Finding(s2, c2, "p", "o", v2)
    apart = Finding(s3, c3, "p", "o", v3, outside="model-specific")
    combined = [Combined(f, f.verdict, (f.verdict,) * 2, 0.0, 0.0) for f in (moved, same, apart)]
    table = _changed(combined, ReplicateSettings(seed=41, seeds=2))
    assert list(table["finding (previous no.)"]) == [n1, n3]
    assert list(table["before"]) == [v1, v3]
    assert list(table["now"]) == [other, f"{v3} (outside the tally)"]
    assert "seed level" in table["why"].iloc[0] and "new seeds 41–42" in table["why"].iloc[0]
