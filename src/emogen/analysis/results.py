"""What each analysis of ``emogen analyse`` returns, and the one renderer that writes the report.

An analysis (one section of the report) returns a :class:`Section`: its content for people
(headings, text, tables, figures: :class:`~emogen.analysis.report.Content`), its entries of
``analysis.json`` (``data``: headline numbers) and its tests as typed :class:`Result` objects —
in the spirit of statsmodels' results and :mod:`emogen.analysis.replication.findings`: an
estimate with its interval, the test (name, statistic, df, p), the unit of inference and how
many of them, the family whose correction it shares, its role in the multiplicity plan
(primary or exploratory, set by :mod:`emogen.analysis.plan`), an effect size with its interval,
and warnings or a failed fit. A section builds each result where it computes the test, by
one path: :meth:`Section.add_test` (a test that ran: its p and the rest as typed arguments) or
:meth:`Section.not_run` (a test the data could not support: its reason). The analysis refuses a
section whose ``data`` holds a record with a p-value (``p``, ``p_perm``, ``p_t``) that neither
registered (:func:`check_registered`, before the plan): no test reaches the report without its typed result, and
none is found by guessing at keys.

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

#: The keys under which a record in ``analysis.json`` holds a p-value: such a record must be a
#: registered test's (:func:`unregistered`).
P_KEYS = ("p", "p_perm", "p_t")

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
        warnings: tuple[str, ...] = (),
        fit: str = "ok",
    ) -> Result:
        """A test as its analysis computed it, added to ``results`` (and returned): ``name``
        as :class:`Result`'s, ``record`` its entry in ``data`` (the role is written into it);
        ``interval``: the estimate's (low, high) at ``level``; ``effect``: a standardised effect
        size (name, value, low, high), its interval at ``level`` too (None, None: none);
        ``warnings`` and ``fit``: the fit's. A p that is not a number is refused: a test that did
        not run is registered by :meth:`not_run`, with its reason."""
        if not _number(p):
            raise ValueError(
                f"test {name!r} has p = {p!r}: a test that did not run is registered with "
                "Section.not_run and its reason"
            )
        size = None
        if effect is not None:
            e_name, value, low, high = effect
            e_int = None if low is None or high is None else Interval(low, high, level)
            size = EffectSize(e_name, value, e_int)
        result = Result(
            name=name,
            family=name.split("[", 1)[0],
            test=HypothesisTest(test, float(p), statistic, df),
            estimate=estimate,
            interval=None if interval is None else Interval(*interval, level),
            unit=unit,
            n=n,
            effect_size=size,
            warnings=tuple(warnings),
            fit=fit,
            record=record,
        )
        self.results.append(result)
        return result

    def not_run(
        self, name: str, reason: str, record: dict[str, Any] | None = None, *, n: int | None = None
    ) -> Result:
        """A test the analysis could not run (too few participants, a fit that failed): in the
        plan as not run with ``reason``, never among the tests that ran nor in a correction's
        family. ``record``: its entry in ``data``, if it has one (a p there must be NaN)."""
        if not reason:
            raise ValueError(f"test {name!r} not run: give the reason")
        result = Result(
            name=name,
            family=name.split("[", 1)[0],
            test=None,
            n=n,
            warnings=(reason,),
            fit="not run",
            record={} if record is None else record,
        )
        self.results.append(result)
        return result


def records_in(data: dict[str, Any], prefix: str = "") -> list[tuple[str, dict[str, Any]]]:
    """Every record with a p-value under ``data``, with its dotted name (where it is; list
    items by their ``emotion``/``group``/``space``/``contrast`` when they have one)."""
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


def unregistered(section: Section) -> list[str]:
    """Where ``section.data`` holds a record with a p-value that is no result of the section
    (neither :meth:`Section.add_test` nor :meth:`Section.not_run` received it)."""
    mine = {id(r.record) for r in section.results}
    return [name for name, record in records_in(section.data) if id(record) not in mine]


def check_registered(sections: list[Section]) -> list[Result]:
    """Every result of ``sections``, or a ValueError naming each record with a p-value in a
    section's ``data`` that the section did not register (the multiplicity plan would miss it)."""
    for s in sections:
        if missing := unregistered(s):
            raise ValueError(
                f"a section's analysis.json entries hold test(s) {missing} that it did not "
                "register (Section.add_test, or Section.not_run with the reason)"
            )
    return [r for s in sections for r in s.results]


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
