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


@dataclass(frozen=True)
class _Figure:
    src: str
    caption: str


Block = _Heading | _Paragraph | _Bullets | _Table | _Figure


@dataclass
class Report:
    """Build with :meth:`heading`, :meth:`paragraph`, :meth:`bullets`, :meth:`table`,
    :meth:`figure`; :meth:`write` puts ``index.html`` and ``README.md`` in ``out``."""

    title: str
    out: Path
    blocks: list[Block] = field(default_factory=list)
    tables: dict[str, Path] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.out = Path(self.out)
        (self.out / "figures").mkdir(parents=True, exist_ok=True)
        (self.out / "tables").mkdir(parents=True, exist_ok=True)

    @property
    def figures(self) -> Path:
        return self.out / "figures"

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
        if name is not None:
            path = self.out / "tables" / f"{name}.csv"
            machine = tidy.machine_table(df if data is None else data, index=index and data is None)
            tidy.write_csv(machine, path, col_types=True)
            self.tables[name] = path
        shown = df.reset_index() if index else df
        self.blocks.append(_Table(shown, caption, name))

    def figure(self, path: Path, caption: str = "") -> None:
        rel = Path(path).resolve().relative_to(self.out.resolve())
        self.blocks.append(_Figure(rel.as_posix(), caption))

    # ---- writing ---------------------------------------------------------------------------
    def _html(self) -> str:
        parts = [
            "<!doctype html>",
            '<html lang="en"><head><meta charset="utf-8">',
            f"<title>{html.escape(self.title)}</title><style>{CSS}</style></head><body>",
            f"<h1>{html.escape(self.title)}</h1>",
        ]
        for b in self.blocks:
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
                    f"<caption>{_inline_html(b.caption)}{link}</caption>"
                    if b.caption or b.name
                    else ""
                )
                parts.append(
                    f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
                )
            else:
                parts.append(
                    f'<figure><img src="{html.escape(b.src)}" alt="{html.escape(b.caption)}">'
                    f"<figcaption>{_inline_html(b.caption)}</figcaption></figure>"
                )
        parts.append("</body></html>")
        return "\n".join(parts) + "\n"

    def _markdown(self) -> str:
        lines = [f"# {self.title}", ""]
        for b in self.blocks:
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

    def write(self) -> tuple[Path, Path]:
        html_path = self.out / "index.html"
        md_path = self.out / "README.md"
        html_path.write_text(self._html())
        md_path.write_text(self._markdown())
        return html_path, md_path
