"""The multiplicity plan of ``emogen analyse``: which tests are primary (named before the
analysis: ``--primary``, default :data:`DEFAULT_PRIMARY`), every other test exploratory.

Every test the report computes is a :class:`~emogen.analysis.results.Result` of its section;
:func:`plan_section` takes them all, marks each ``role`` = ``primary`` or ``exploratory`` (in
the JSON too), adjusts the primary family by Holm (1979) — the only family-wise claim the report
makes across sections — and writes one table of every test with its estimate and interval.
Exploratory p-values are descriptive: each table's own correction (Holm over emotions, max-T
over genes, …) controls that table only. A named primary test the data could not support is
listed as not run, with its reason, never dropped silently — and so is every test a section
registered as not run (:meth:`~emogen.analysis.results.Section.not_run`: too few participants,
a fit that failed): named with its reason, outside the table of tests that ran and outside
the primary family Holm's adjustment counts.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from emogen.analysis.results import Result, Section
from emogen.errors import ConfigError

if TYPE_CHECKING:
    from pathlib import Path

#: The primary test when none is named: the own-distance model's contrast (its primary fit).
DEFAULT_PRIMARY = ("categorisation.own_distance.primary",)
#: Tests that may be named primary (a name covers every test under it, e.g. one per emotion).
PLANNABLE = (
    "categorisation.own_distance.primary",
    "categorisation.own_distance.gee",
    "categorisation.own_distance.two_stage",
    "categorisation.own_distance.control",
    "categorisation.own_advantage",
    "categorisation.fields_accuracy",
    "categorisation.hit_rates",
    "conditions.emotion",
    "conditions.identity",
    "conditions.emotion × identity",
    "identity.distance",
    "spread_test",
    "spread_empirical",
)


def check_primary(names: tuple[str, ...]) -> tuple[str, ...]:
    """``names`` if each is a plannable test (:data:`PLANNABLE`), else a ConfigError naming it."""
    for name in names:
        if name not in PLANNABLE:
            raise ConfigError(
                f"--primary {name!r} is not a test of emogen analyse; the tests that can be "
                f"primary: {', '.join(PLANNABLE)}"
            )
    if len(set(names)) != len(names):
        raise ConfigError(f"--primary names a test twice: {list(names)}")
    return names


def mark_roles(results: list[Result], primary: tuple[str, ...]) -> list[Result]:
    """``results`` with each ``role`` set: primary where ``primary`` names it (or a name above
    it), else exploratory (the records in ``analysis.json`` say so too)."""
    return [
        r.with_role("primary" if any(_under(r.name, n) for n in primary) else "exploratory")
        for r in results
    ]


def plan_table(results: list[Result]) -> pd.DataFrame:
    """One row per test that ran (tests not run are left out): ``test``, ``role``, ``p``,
    ``p_holm_primary`` (primary only), ``estimate``, ``ci_low``, ``ci_high``, ``effect_size``
    (standardised, where the test gives one); primary first."""
    rows = [
        {
            "test": r.name,
            "role": r.role,
            "p": r.p,
            "estimate": r.estimate,
            "ci_low": None if r.interval is None else r.interval.low,
            "ci_high": None if r.interval is None else r.interval.high,
            "effect_size": None if r.effect_size is None else r.effect_size.value,
        }
        for r in results
        if r.test is not None
    ]
    table = pd.DataFrame(
        rows, columns=["test", "role", "p", "estimate", "ci_low", "ci_high", "effect_size"]
    )
    table.insert(3, "p_holm_primary", _holm(table))
    primary_first = table.sort_values("role", key=lambda r: r != "primary", kind="stable")
    return primary_first.reset_index(drop=True)


def _under(path: str, name: str) -> bool:
    return path == name or path.startswith(f"{name}.") or path.startswith(f"{name}[")


def _holm(table: pd.DataFrame) -> pd.Series:
    """Holm-adjusted p over the primary tests with a p (NA elsewhere)."""
    out = pd.Series(np.nan, index=table.index, dtype=float)
    mask = (table["role"] == "primary") & table["p"].notna()
    if not mask.any():
        return out
    p = table.loc[mask, "p"].to_numpy(dtype=float)
    order = np.argsort(p)
    m = len(p)
    adjusted = np.maximum.accumulate(np.minimum(1.0, (m - np.arange(m)) * p[order]))
    result = np.empty(m)
    result[order] = adjusted
    out[mask] = result
    return out


def plan_section(results: list[Result], primary: tuple[str, ...], out: Path) -> Section:
    """The report's multiplicity plan (``analysis.json``'s ``plan``) over every test of the
    report (``results``, their roles set by :func:`mark_roles`)."""
    sec = Section(out)
    table = plan_table(results)
    not_run: list[tuple[str, str, str]] = [
        (r.name, r.role, "; ".join(r.warnings)) for r in results if r.test is None
    ]
    missing = [
        (n, "primary", "no section registered it (see its section)")
        for n in primary
        if not any(_under(t, n) for t in [*table["test"], *(name for name, _, _ in not_run)])
    ]
    not_run = sorted(not_run + missing, key=lambda row: row[1] != "primary")
    sec.data["plan"] = {
        "primary": list(primary),
        "not_run": [{"test": n, "role": role, "reason": why} for n, role, why in not_run],
        "tests": table.astype(object).where(table.notna(), None).to_dict(orient="records"),
    }
    sec.heading("Multiplicity plan: primary and exploratory tests")
    named = ", ".join(f"`{n}`" for n in primary) or "none"
    sec.paragraph(
        f"Primary test(s), named before the analysis (`--primary`): {named}; the family-wise "
        "error over them is held by Holm's method (`p_holm_primary`). Every other test is "
        "exploratory: its p-value describes, and its own table's correction (where it has "
        "one) controls that table only. Estimates and intervals are on each test's own scale "
        "(see its section); `effect_size` is standardised where the test gives one (dz: mean "
        "difference over the SD of the participants' differences; r; R²; partial η², "
        "bias-corrected, for the condition tests)."
    )
    if any(role == "primary" for _, role, _ in not_run):
        sec.paragraph(
            "**Named primary test(s) not run** (the data could not support them): "
            + ", ".join(f"`{n}`" for n, role, _ in not_run if role == "primary")
            + ". Holm's adjustment counts only the primary tests that ran."
        )
    sec.table(table, "plan", f"Every test of this report that ran ({len(table)}), primary first")
    if not_run:
        rows = pd.DataFrame(not_run, columns=["test", "role", "reason"])
        sec.table(
            rows,
            "plan_not_run",
            f"Tests not run ({len(rows)}): not among the tests above, nor in any correction",
        )
    return sec
