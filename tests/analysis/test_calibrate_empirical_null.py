"""benchmarks/calibrate_empirical_null.py: the intervals it prints beside a flagged count are
statsmodels' (Wilson and the exact Clopper–Pearson), and a cell's line says whether the
flagged share passes α + 2 SE — checked on counts where the answer is known."""

from __future__ import annotations

import pytest
from benchmarks.calibrate_empirical_null import cell_line, clopper_pearson, wilson
from statsmodels.stats.proportion import proportion_confint


@pytest.mark.parametrize(("k", "n"), [(0, 40), (1, 40), (9, 200), (24, 400), (40, 40)])
def test_intervals_equal_statsmodels(k: int, n: int) -> None:
    assert wilson(k, n) == pytest.approx(proportion_confint(k, n, method="wilson"), abs=1e-6)
    assert clopper_pearson(k, n) == pytest.approx(proportion_confint(k, n, method="beta"), abs=1e-9)


def test_a_null_cell_passes_only_at_most_alpha_plus_two_se() -> None:
    # 200 tests: bound 0.05 + 2 sqrt(0.05 · 0.95 / 200) = 0.0808; 16 of 200 = 0.08 passes,
    # 17 of 200 = 0.085 does not; interval coverage is the share of True second entries
    passing = [[(True, True)]] * 16 + [[(False, True)]] * 183 + [[(False, False)]]
    failing = [[(True, True)]] * 17 + [[(False, True)]] * 183
    assert "bound α + 2 SE = 0.081 (within); interval covers 0 in 99.5%" in cell_line(
        0.0, 20, passing, 1.0
    )
    assert "(ABOVE)" in cell_line(0.0, 20, failing, 1.0)
    # a cell with individual differences is power: no bound
    assert "bound" not in cell_line(0.1, 20, failing, 1.0)
    assert "flagged 17 of 200 tests = 0.085" in cell_line(0.1, 20, failing, 1.0)
