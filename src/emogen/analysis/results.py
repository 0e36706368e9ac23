"""What each analysis of ``emogen analyse`` returns, and the one renderer that writes the report.

An analysis (one section of the report) returns a :class:`Section`: its content for people
(headings, text, tables, figures: :class:`~emogen.analysis.report.Content`), its entries of
``analysis.json`` (``data``: headline numbers) and its tests as typed :class:`Result` objects —
in the spirit of statsmodels' results and :mod:`emogen.analysis.replication.findings`: an
estimate with its interval, the test (name, statistic, df, p), the unit of inference and how
many of them, the family whose correction it shares, its role in the multiplicity plan
(primary or exploratory, set by :mod:`emogen.analysis.plan`), an effect size with its interval,
and warnings or a failed fit. A section builds each result where it computes the test
(:meth:`Section.add_test`); sections written before that read theirs from their records in
``data`` (:meth:`Section.tests_in_data`, by the ``*_KEYS`` below: a p-value under another key
is not found there, so a new analysis uses ``add_test``).

:func:`write_analysis` is the one renderer: from the sections it writes ``index.html``,
``README.md``, every table under ``tables/`` and ``analysis.json`` (each test's record there
carries its ``role``). Figures are made by the sections, under ``figures/``, and referenced.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from emogen.analysis.report import Content, write_pages

#: The keys of a test's record in ``analysis.json`` that hold, in order of preference, ...
P_KEYS = ("p", "p_perm", "p_t")  # its p-value
ESTIMATE_KEYS = ("contrast", "difference", "mean_difference", "mean_contrast", "r", "excess")
STATISTIC_KEYS = ("t", "z", "F", "chi2", "statistic")
N_KEYS = ("n_participants", "n")
EFFECT_KEYS = (("dz", "dz_low", "dz_high"), ("r", "ci_low", "ci_high"))

Role = Literal["primary", "exploratory"]


@dataclass(frozen=True)
class Interval:
    low: float
    high: float
    #: e.g. 0.95; None where the analysis's record does not say (never guessed)
    level: float | None


@dataclass(frozen=True)
class HypothesisTest:
    name: str  # e.g. "t", "z", "permutation"
    p: float
    statistic: float | None = None
    df: float | None = None


@dataclass(frozen=True)
class EffectSize:
    name: str  # "dz", "r"
    value: float
    interval: Interval | None = None


@dataclass(frozen=True)
class Result:
    """One test of the report. ``name``: where its record is in ``analysis.json`` (dotted, a
    list item by its emotion/group in brackets: ``spread_test[happy]``); ``family``: the table
    whose own correction it shares (its name without the item); ``record``: the numbers as
    ``analysis.json`` gives them (every field of the test's own kind)."""

    name: str
    family: str
    test: HypothesisTest | None
    estimate: float | None = None
    interval: Interval | None = None
    unit: str = "participant"
    n: int | None = None
    role: Role = "exploratory"
    effect_size: EffectSize | None = None
    warnings: tuple[str, ...] = ()
    fit: str = "ok"  # "ok", or the fit's status (e.g. "failed") with ``warnings`` saying why
    record: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @property
    def p(self) -> float | None:
        return None if self.test is None else self.test.p

    def with_role(self, role: Role) -> Result:
        self.record["role"] = role  # the JSON record says it too
        return replace(self, role=role)


@dataclass
class Section(Content):
    """What one analysis returns: content, ``data`` (its entries of ``analysis.json``) and
    ``results`` (its tests). Build the content as a report's (:class:`Content`)."""

    data: dict[str, Any] = field(default_factory=dict)
    results: list[Result] = field(default_factory=list)

    def test(self, name: str, record: dict[str, Any], unit: str = "participant") -> None:
        """The test whose record (in ``data``) is ``record``, as a :class:`Result`."""
        self.results.append(result_of(name, record, unit))

    def add_test(
        self,
        name: str,
        record: dict[str, Any],
        *,
        test: str,
        p: float,
        n: int | None,
        statistic: float | None = None,
        df: float | None = None,
        unit: str = "participant",
        estimate: float | None = None,
        interval: tuple[float, float] | None = None,
        level: float | None = None,
        effect: tuple[str, float, float | None, float | None] | None = None,
    ) -> Result:
        """A test as its analysis computed it, added to ``results`` (and returned): ``name``
        as :class:`Result`'s, ``record`` its entry in ``data`` (the role is written into it);
        ``interval``: the estimate's (low, high) at ``level``; ``effect``: a standardised effect
        size (name, value, low, high), its interval at ``level`` too (None, None: none)."""
        size = None
        if effect is not None:
            e_name, value, low, high = effect
            e_int = None if low is None or high is None else Interval(low, high, level)
            size = EffectSize(e_name, value, e_int)
        result = Result(
            name=name,
            family=name.split("[", 1)[0],
            test=HypothesisTest(test, p, statistic, df),
            estimate=estimate,
            interval=None if interval is None else Interval(*interval, level),
            unit=unit,
            n=n,
            effect_size=size,
            record=record,
        )
        self.results.append(result)
        return result

    def tests_in_data(self, unit: str = "participant") -> Section:
        """Every record in ``data`` with a p-value as a :class:`Result` (an analysis that fills
        ``data`` only); returns the section."""
        self.results += [result_of(n, r, unit) for n, r in records_in(self.data)]
        return self


def result_of(name: str, record: dict[str, Any], unit: str = "participant") -> Result:
    """A test's :class:`Result` from its record in ``analysis.json`` (see the ``*_KEYS``); the
    record's own ``unit`` overrides ``unit``."""
    p = _first(record, P_KEYS)
    stat_key = next((k for k in STATISTIC_KEYS if _number(record.get(k))), None)
    level = float(record["confidence"]) if _number(record.get("confidence")) else None
    both = _number(record.get("ci_low")) and _number(record.get("ci_high"))
    interval = Interval(float(record["ci_low"]), float(record["ci_high"]), level) if both else None
    test = None
    if p is not None:
        test = HypothesisTest(
            name=str(record.get("test", stat_key or "test")),
            p=float(p),
            statistic=None if stat_key is None else float(record[stat_key]),
            df=float(record["df"]) if _number(record.get("df")) else None,
        )
    n = _first(record, N_KEYS)
    warnings = record.get("warnings") or ()
    return Result(
        name=name,
        family=name.split("[", 1)[0],
        test=test,
        estimate=_first(record, ESTIMATE_KEYS),
        interval=interval,
        unit=str(record.get("unit", unit)),
        n=int(n) if _number(n) else None,
        effect_size=_effect(record, level),
        warnings=tuple(str(w) for w in warnings) if isinstance(warnings, list | tuple) else (),
        fit=str(record.get("status", "ok")),
        record=record,
    )


def records_in(data: dict[str, Any], prefix: str = "") -> list[tuple[str, dict[str, Any]]]:
    """Every record with a p-value under ``data``, with its dotted name; list items are named
    by their ``emotion``/``group``/``space``/``contrast`` when they have one."""
    found: list[tuple[str, dict[str, Any]]] = []

    def walk(node: object, path: str) -> None:
        if isinstance(node, dict):
            if any(k in node for k in P_KEYS) and path:
                found.append((path, node))
            for key, value in node.items():
                walk(value, f"{path}.{key}" if path else str(key))
        elif isinstance(node, list):
            for i, value in enumerate(node):
                walk(value, f"{path}[{_item_name(value, i)}]")

    walk(data, prefix)
    return found


def _item_name(value: object, i: int) -> str:
    if isinstance(value, dict):
        for key in ("emotion", "group", "space", "contrast"):
            if key in value:
                return str(value[key])
    return str(i)


def _number(value: object) -> bool:
    return (
        isinstance(value, int | float | np.integer | np.floating)
        and not isinstance(value, bool)
        and bool(np.isfinite(float(value)))
    )


def _first(record: dict[str, Any], keys: tuple[str, ...]) -> Any:
    for key in keys:
        value = record.get(key)
        if value is not None:
            return value
    return None


def _effect(record: dict[str, Any], level: float | None) -> EffectSize | None:
    for name, lo, hi in EFFECT_KEYS:
        if _number(record.get(name)):
            both = _number(record.get(lo)) and _number(record.get(hi))
            interval = Interval(float(record[lo]), float(record[hi]), level) if both else None
            return EffectSize(name, float(record[name]), interval)
    return None


# ---- the renderer ----------------------------------------------------------------------------
def write_analysis(
    title: str, out: Path, sections: list[Section], data: dict[str, Any]
) -> tuple[Path, Path, Path]:
    """The report of ``sections`` in ``out``: ``index.html``, ``README.md``, ``tables/*.csv``
    and ``analysis.json`` (``data``, then every section's entries, in order)."""
    blocks = [b for s in sections for b in s.blocks]
    html_path, md_path = write_pages(title, Path(out), blocks)
    merged = dict(data)
    for s in sections:
        merged.update(s.data)
    json_path = Path(out) / "analysis.json"
    json_path.write_text(json.dumps(merged, indent=2, default=_json) + "\n")
    return html_path, md_path, json_path


def _json(o: object) -> object:
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)
