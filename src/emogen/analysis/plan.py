"""The multiplicity plan of ``emogen analyse``: which tests are primary (named before the
analysis: ``--primary``, default :data:`DEFAULT_PRIMARY`), every other test exploratory.

Every test the report computes leaves a record in ``analysis.json`` (a dict with a p-value);
:func:`plan_section` finds them all, marks each ``role`` = ``primary`` or ``exploratory`` in
the JSON, adjusts the primary family by Holm (1979) — the only family-wise claim the report
makes across sections — and writes one table of every test with its estimate and interval.
Exploratory p-values are descriptive: each table's own correction (Holm over emotions, max-T
over genes, …) controls that table only. A named primary test the data could not support is
listed as not run, with its reason, never dropped silently.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from emogen.errors import ConfigError

if TYPE_CHECKING:
    from emogen.analysis.report import Report

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
_P = ("p", "p_perm", "p_t")
_ESTIMATE = ("contrast", "difference", "mean_difference", "mean_contrast", "r", "excess")


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


def collect_tests(summary: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """Every test record in ``summary`` (a dict with a p-value), with its dotted path; list
    items are named by their ``emotion``/``group``/``space`` when they have one."""
    found: list[tuple[str, dict[str, Any]]] = []

    def walk(node: object, path: str) -> None:
        if isinstance(node, dict):
            if any(k in node for k in _P) and path:
                found.append((path, node))
            for key, value in node.items():
                walk(value, f"{path}.{key}" if path else str(key))
        elif isinstance(node, list):
            for i, value in enumerate(node):
                name = _item_name(value, i)
                walk(value, f"{path}[{name}]")

    walk({k: v for k, v in summary.items() if k != "plan"}, "")
    return found


def _item_name(value: object, i: int) -> str:
    if isinstance(value, dict):
        for key in ("emotion", "group", "space", "contrast"):
            if key in value:
                return str(value[key])
    return str(i)


def _first(record: dict[str, Any], keys: tuple[str, ...]) -> Any:
    for key in keys:
        value = record.get(key)
        if value is not None:
            return value
    return None


def plan_table(summary: dict[str, Any], primary: tuple[str, ...]) -> pd.DataFrame:
    """One row per test: ``test``, ``role``, ``p``, ``p_holm_primary`` (primary only),
    ``estimate``, ``ci_low``, ``ci_high``, ``effect_size`` (standardised, where the test gives
    one); marks ``role`` in each record of ``summary``."""
    rows = []
    for path, record in collect_tests(summary):
        role = "primary" if any(_under(path, name) for name in primary) else "exploratory"
        record["role"] = role
        rows.append(
            {
                "test": path,
                "role": role,
                "p": _first(record, _P),
                "estimate": _first(record, _ESTIMATE),
                "ci_low": record.get("ci_low"),
                "ci_high": record.get("ci_high"),
                "effect_size": _first(record, ("dz", "r")),
            }
        )
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


def plan_section(report: Report, summary: dict[str, Any], primary: tuple[str, ...]) -> None:
    """The report's multiplicity plan (``summary["plan"]``)."""
    table = plan_table(summary, primary)
    missing = [n for n in primary if not any(_under(t, n) for t in table["test"])]
    summary["plan"] = {
        "primary": list(primary),
        "not_run": missing,
        "tests": table.astype(object).where(table.notna(), None).to_dict(orient="records"),
    }
    report.heading("Multiplicity plan: primary and exploratory tests")
    named = ", ".join(f"`{n}`" for n in primary) or "none"
    report.paragraph(
        f"Primary test(s), named before the analysis (`--primary`): {named}; the family-wise "
        "error over them is held by Holm's method (`p_holm_primary`). Every other test is "
        "exploratory: its p-value describes, and its own table's correction (where it has "
        "one) controls that table only. Estimates and intervals are on each test's own scale "
        "(see its section); `effect_size` is standardised where the test gives one (dz: mean "
        "difference over the SD of the participants' differences; r)."
    )
    if missing:
        report.paragraph(
            "**Named primary test(s) not run** (the data could not support them; their "
            "sections say why): " + ", ".join(f"`{n}`" for n in missing) + "."
        )
    report.table(table, "plan", f"Every test of this report ({len(table)}), primary first")
