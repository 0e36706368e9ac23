"""A small report writer: one structure, written as HTML (``index.html``) and Markdown
(``README.md``), with figures under ``figures/`` and every table also as CSV under ``tables/``
(for R users: ``read.csv("tables/<name>.csv")``): long format, one value per cell, identifier
headers; display formatting (rounding, ``–``, pivots) only in the HTML and Markdown.

Text may use two inline marks, rendered in both outputs: ``code`` in backticks and **bold**.
"""

from __future__ import annotations

import html
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from emogen import columns as tidy

CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:1100px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.6em}h2{font-size:1.3em;border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:2em}
h3{font-size:1.1em}table{border-collapse:collapse;margin:.6em 0 1.2em;font-size:.85em}
td,th{border:1px solid #ccc;padding:.25em .5em;text-align:left}th{background:#f3f3f3}
td.n{text-align:right}caption{caption-side:top;text-align:left;
font-size:.9em;color:#555;padding:.2em 0}figure{margin:1em 0}figcaption{font-size:.85em;color:#555}
img{max-width:100%}code{background:#f4f4f4;padding:0 .2em}.csv{font-size:.8em}
.holds{color:#1a7f37;font-weight:600}.differs{color:#b3261e;font-weight:600}
.partly{color:#9a6700;font-weight:600}
"""


def fmt(value: object) -> str:
    """Numbers at a readable precision; everything else as text."""
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        v = float(value)
        if np.isnan(v):
            return "–"
        if v == 0:
            return "0"
        if abs(v) >= 1000:
            return f"{v:,.0f}"
        if abs(v) >= 0.01:
            return f"{v:.3f}"
        return f"{v:.2g}"
    return "" if value is None else str(value)


def _inline_html(text: str) -> str:
    out = html.escape(text)
    out = re.sub(r"`([^`]+)`", r"<code>\1</code>", out)
    out = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", out)
    for word in ("holds", "differs", "partly"):
        out = out.replace(f"<strong>{word}</strong>", f'<strong class="{word}">{word}</strong>')
    return out


def _cell(value: object) -> str:
    """A table cell: numbers right-aligned, text left."""
    numeric = isinstance(value, int | float | np.integer | np.floating) and not isinstance(
        value, bool | np.bool_
    )
    return ('<td class="n">' if numeric else "<td>") + f"{_inline_html(fmt(value))}</td>"


def _md_cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


@dataclass(frozen=True)
class _Heading:
    level: int
    text: str


@dataclass(frozen=True)
class _Paragraph:
    text: str


@dataclass(frozen=True)
class _Bullets:
    items: list[str]


@dataclass(frozen=True)
class _Table:
    df: pd.DataFrame
    caption: str
    name: str | None
    #: the table for machines (``tables/<name>.csv``); None: not written
    machine: pd.DataFrame | None = None
    shown: bool = True


@dataclass(frozen=True)
class _Figure:
    src: str
    caption: str


Block = _Heading | _Paragraph | _Bullets | _Table | _Figure


@dataclass
class Content:
    """A report's content, built with :meth:`heading`, :meth:`paragraph`, :meth:`bullets`,
    :meth:`table`, :meth:`csv` and :meth:`figure`; figures are saved under ``out/figures`` by
    whoever makes them, tables are written when the content is (:func:`write_tables`)."""

    out: Path
    blocks: list[Block] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.out = Path(self.out)
        (self.out / "figures").mkdir(parents=True, exist_ok=True)
        (self.out / "tables").mkdir(parents=True, exist_ok=True)

    @property
    def figures(self) -> Path:
        return self.out / "figures"

    @property
    def tables(self) -> dict[str, Path]:
        """The CSV file of each named table, by name."""
        return {
            b.name: self.out / "tables" / f"{b.name}.csv"
            for b in self.blocks
            if isinstance(b, _Table) and b.name is not None and b.machine is not None
        }

    def heading(self, text: str, level: int = 2) -> None:
        self.blocks.append(_Heading(level, text))

    def paragraph(self, text: str) -> None:
        self.blocks.append(_Paragraph(text))

    def insert_paragraph(self, index: int, text: str) -> None:
        """A paragraph at position ``index`` of what was added so far (a summary at the top)."""
        self.blocks.insert(index, _Paragraph(text))

    def bullets(self, items: list[str]) -> None:
        if items:
            self.blocks.append(_Bullets(list(items)))

    def table(
        self,
        df: pd.DataFrame,
        name: str | None = None,
        caption: str = "",
        *,
        index: bool = False,
        data: pd.DataFrame | None = None,
    ) -> None:
        """A table in the report; with ``name`` also ``tables/<name>.csv``: ``data`` (else the
        table) for machines, full precision, long format with identifier headers
        (:func:`emogen.columns.machine_table`; ``index``: a matrix, written long)."""
        machine = None
        if name is not None:
            machine = tidy.machine_table(df if data is None else data, index=index and data is None)
        shown = df.reset_index() if index else df
        self.blocks.append(_Table(shown, caption, name, machine))

    def csv(self, frame: pd.DataFrame, name: str) -> None:
        """``tables/<name>.csv`` written as ``frame`` is, not shown in the report (too many
        rows, or a table for machines only)."""
        self.blocks.append(_Table(frame, "", name, frame, shown=False))

    def figure(self, path: Path, caption: str = "") -> None:
        rel = Path(path).resolve().relative_to(self.out.resolve())
        self.blocks.append(_Figure(rel.as_posix(), caption))


class Report(Content):
    """A whole report: its title and content; :meth:`write` puts ``index.html`` and
    ``README.md`` in ``out`` and every named table under ``tables/``."""

    def __init__(self, title: str, out: Path) -> None:
        super().__init__(Path(out))
        self.title = title

    def write(self) -> tuple[Path, Path]:
        return write_pages(self.title, self.out, self.blocks)


def write_tables(out: Path, blocks: list[Block]) -> None:
    """Every named table of ``blocks`` as ``out/tables/<name>.csv`` (with its readr types)."""
    for b in blocks:
        if isinstance(b, _Table) and b.name is not None and b.machine is not None:
            tidy.write_csv(b.machine, Path(out) / "tables" / f"{b.name}.csv", col_types=True)


def write_pages(title: str, out: Path, blocks: list[Block]) -> tuple[Path, Path]:
    """``blocks`` as ``index.html`` and ``README.md`` in ``out``, their tables as CSV."""
    write_tables(out, blocks)
    shown = [b for b in blocks if not (isinstance(b, _Table) and not b.shown)]
    html_path = Path(out) / "index.html"
    md_path = Path(out) / "README.md"
    html_path.write_text(_html(title, shown))
    md_path.write_text(_markdown(title, shown))
    return html_path, md_path


# ---- writing -------------------------------------------------------------------------------
def _html(title: str, blocks: list[Block]) -> str:
    parts = [
        "<!doctype html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title><style>{CSS}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
    ]
    for b in blocks:
        if isinstance(b, _Heading):
            parts.append(f"<h{b.level}>{_inline_html(b.text)}</h{b.level}>")
        elif isinstance(b, _Paragraph):
            parts.append(f"<p>{_inline_html(b.text)}</p>")
        elif isinstance(b, _Bullets):
            items = "".join(f"<li>{_inline_html(i)}</li>" for i in b.items)
            parts.append(f"<ul>{items}</ul>")
        elif isinstance(b, _Table):
            head = "".join(f"<th>{html.escape(str(c))}</th>" for c in b.df.columns)
            body = "".join(
                "<tr>" + "".join(_cell(v) for v in row) + "</tr>"
                for row in b.df.itertuples(index=False)
            )
            link = f' <a class="csv" href="tables/{b.name}.csv">CSV</a>' if b.name else ""
            cap = (
                f"<caption>{_inline_html(b.caption)}{link}</caption>" if b.caption or b.name else ""
            )
            parts.append(f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
        else:
            parts.append(
                f'<figure><img src="{html.escape(b.src)}" alt="{html.escape(b.caption)}">'
                f"<figcaption>{_inline_html(b.caption)}</figcaption></figure>"
            )
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def _markdown(title: str, blocks: list[Block]) -> str:
    lines = [f"# {title}", ""]
    for b in blocks:
        if isinstance(b, _Heading):
            lines += ["#" * b.level + " " + b.text, ""]
        elif isinstance(b, _Paragraph):
            lines += [b.text, ""]
        elif isinstance(b, _Bullets):
            lines += [f"* {i}" for i in b.items] + [""]
        elif isinstance(b, _Table):
            if b.caption or b.name:
                link = f" ([CSV](tables/{b.name}.csv))" if b.name else ""
                lines += [f"*{b.caption}*{link}" if b.caption else link.strip(), ""]
            lines.append("| " + " | ".join(_md_cell(str(c)) for c in b.df.columns) + " |")
            lines.append("|" + "---|" * len(b.df.columns))
            for row in b.df.itertuples(index=False):
                lines.append("| " + " | ".join(_md_cell(fmt(v)) for v in row) + " |")
            lines.append("")
        else:
            lines += [f"![{b.caption}]({b.src})", "", f"*{b.caption}*", ""]
    return "\n".join(lines)
