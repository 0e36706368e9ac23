"""The report writer: HTML and Markdown from one structure, tables as CSV."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from emogen.analysis.report import Report, fmt


def test_report_writes_html_markdown_and_csv(tmp_path: Path) -> None:
    r = Report("A <title>", tmp_path / "rep")
    r.heading("Section")
    r.paragraph("Uses `code`, **bold** and **holds**; 1 < 2.")
    r.bullets(["one", "two"])
    df = pd.DataFrame({"x": [1, 2], "y": [0.123456, np.nan], "ok": [True, False]})
    r.table(df, "numbers", "Some | numbers")
    fig = r.figures / "f.png"
    fig.write_bytes(b"\x89PNG")
    r.figure(fig, "a figure")
    html_path, md_path = r.write()
    html = html_path.read_text()
    assert "<title>A &lt;title&gt;</title>" in html
    assert "<code>code</code>" in html and '<strong class="holds">holds</strong>' in html
    assert "1 &lt; 2" in html and 'src="figures/f.png"' in html
    assert '<td class="n">0.123</td>' in html and "<td>yes</td>" in html and ">–</td>" in html
    md = md_path.read_text()
    assert "| x | y | ok |" in md and "*Some | numbers*" in md
    assert "![a figure](figures/f.png)" in md
    back = pd.read_csv(tmp_path / "rep" / "tables" / "numbers.csv")
    assert back["y"].iloc[0] == 0.123456


def test_fmt() -> None:
    assert fmt(3) == "3" and fmt(0.0) == "0" and fmt(0.00123) == "0.0012"
    assert fmt(12345.6) == "12,346" and fmt(None) == "" and fmt("s") == "s"
